//! Issue 14 item 4: the bad-input table. One row per bad input across every command — recording
//! files, flags, configs, tables, NC programs, toolpaths, FRF tables, shank configs. Each row is
//! run in a fresh folder holding only its input files and asserts:
//!
//! * the exit code (1: refused; never a panic) and an empty standard output (also with `--json -`),
//! * that the message names the problem and where (`file:line[:column]`, the flag or the key),
//! * that each cause is printed once (no `: `-separated part of the message repeated),
//! * that no input file changed (a hash of every file before and after),
//! * that nothing is left behind: the folder holds exactly the input files afterwards, although
//!   most rows ask for outputs (`--json`, `--out`, `--plot`, `--plots`, `--plot-dir`), so a job
//!   that fails halfway leaves neither its finished outputs nor temporary files.

use std::collections::BTreeMap;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::{Path, PathBuf};

use crate::common;
use common::*;

/// Content of an input file of a row.
enum Src {
    /// Text as given.
    Text(&'static str),
    /// Raw bytes.
    Bytes(&'static [u8]),
    /// A copy of a file under `examples/`.
    Example(&'static str),
    /// A copy of an example with one replacement (`from` → `to`, `from` must occur).
    Edit(&'static str, &'static str, &'static str),
    /// A folder, where a file is expected.
    Folder,
}
use Src::*;

/// One bad input.
struct Row {
    /// What is wrong.
    name: &'static str,
    /// Input files written into the row's folder.
    files: &'static [(&'static str, Src)],
    /// The command line; `{d}` is the row's folder.
    args: &'static str,
    /// Texts the error message must contain: the problem and where it is.
    expect: &'static [&'static str],
}

const SIM: &str =
    "simulate --teeth 4 --diameter-mm 10 --rpm 3240 --fz-mm 0.08 --ap-mm 1 --ae-mm 2 \
                   --mode down --ktc 1889.2 --krc 806.1";
const SIM_OUT: &str = "--out {d}/forces.csv --json {d}/sim.json --plot {d}/forces.svg";
const IDENTIFY: &str =
    "identify {d}/rec.csv --config {d}/cut.toml --json {d}/id.json --plot-dir {d}/plots";
const CUT: (&str, Src) = (
    "cut.toml",
    Edit("identify/cut.toml", "fz_mm = [0.05, 0.08]", "fz_mm = 0.05"),
);
const SHANK_CFG: (&str, Src) = ("shank.toml", Text(SHANK_TOML));
const SHANK_TOML: &str = include_str!("../data/shank.toml");
const SHANK_REC: (&str, Src) = (
    "rec.csv",
    Text(include_str!("../data/issue20/shank_recording.csv")),
);
const GRIND: &str = "grind compensate --probe {d}/probe.csv --bar-diameter-mm 6 --probe-tip-radius-mm 1 \
                     --edge {d}/edge.csv --json {d}/g.json --path-out {d}/path.csv --plots {d}/plots";
const PROBE: (&str, Src) = ("probe.csv", Example("grind/probe.csv"));
const EDGE: (&str, Src) = ("edge.csv", Example("grind/edge.csv"));
const FLUTE: (&str, Src) = ("flute.nc", Example("grind/flute.nc"));
const SIGNAL: &str = "time_s,disp_a_um\n0,1\n0.001,2\n0.002,3\n0.003,2\n0.004,1\n";

#[rustfmt::skip]
const ROWS: &[Row] = &[
    // ---- recordings (identify) ----
    Row { name: "empty recording", files: &[("rec.csv", Text("")), CUT], args: IDENTIFY,
          expect: &["rec.csv", "empty"] },
    Row { name: "empty Parquet recording", files: &[("rec.parquet", Text("")), CUT],
          args: "identify {d}/rec.parquet --config {d}/cut.toml --json {d}/id.json",
          expect: &["rec.parquet", "empty", "Parquet file"] },
    Row { name: "binary recording", files: &[("rec.csv", Bytes(b"PK\x03\x04\x00\x00\x08\x00\xff\xfe")), CUT],
          args: IDENTIFY, expect: &["rec.csv:1", "binary"] },
    Row { name: "row with a missing field", files: &[("rec.csv", Text("time_s,Fx,Fy,Fz\n0,1,2,3\n0.001,1.5,2\n")), CUT],
          args: IDENTIFY, expect: &["rec.csv:3", "expected 4 fields, found 3"] },
    Row { name: "NaN in a recording", files: &[("rec.csv", Text("time_s,Fx,Fy,Fz\n0,1,2,3\n0.001,nan,2,3\n")), CUT],
          args: IDENTIFY, expect: &["rec.csv:3:2", "`nan`", "not a finite number"] },
    Row { name: "time going back", files: &[("rec.csv", Text("time_s,Fx,Fy,Fz\n0,1,2,3\n0.001,1,2,3\n0.0005,1,2,3\n")), CUT],
          args: IDENTIFY, expect: &["rec.csv:4:1", "time must increase"] },
    Row { name: "no time column and no rate", files: &[("rec.csv", Text("fx_N,fy_N\n1,2\n1,2\n")), CUT],
          args: IDENTIFY, expect: &["rec.csv", "no sample rate", "--sample-rate-hz"] },
    Row { name: "recording is a folder", files: &[("rec.csv", Folder), CUT], args: IDENTIFY,
          expect: &["rec.csv", "cannot read", "expected a file, got a folder"] },
    Row { name: "recording does not exist", files: &[CUT], args: IDENTIFY,
          expect: &["rec.csv", "No such file", "check the path"] },
    Row { name: "axis mapping names no channel", files: &[("rec.csv", Text("time_s,fx_N,fy_N\n0,1,2\n0.001,1,2\n")), CUT],
          args: "identify {d}/rec.csv --config {d}/cut.toml --axes x=Fq --json {d}/id.json",
          expect: &["Fq"] },
    Row { name: "one absurd force cell", files: &[("rec.txt", Edit("identify/cut_fz0.05.txt", "\n0.1988,-4.3441,", "\n0.1988,1e308,")), CUT],
          args: "identify {d}/rec.txt --config {d}/cut.toml --json {d}/id.json --plot-dir {d}/plots",
          expect: &["rec.txt:2000:2:", "sample 1989", "t = 0.1988 s", "`Fx`", "column 2", "1e308", "more than 1e9 N"] },
    Row { name: "absurd force after blank lines", files: &[("rec.csv", Text("time_s,Fx,Fy,Fz\n0,1,2,3\n\n \n0.001,1,2,3\n0.002,1,-3e9,3\n")), CUT],
          args: IDENTIFY, expect: &["rec.csv:6:3:", "sample 3", "`Fy`", "column 3", "-3e9", "more than 1e9 N"] },
    Row { name: "negative sample rate", files: &[("rec.csv", Text("fx_N,fy_N\n1,2\n1,2\n")), CUT],
          args: "identify {d}/rec.csv --config {d}/cut.toml --sample-rate-hz=-5 --json {d}/id.json",
          expect: &["rec.csv", "--sample-rate-hz", "-5"] },
    // ---- identify configs and FRF tables ----
    Row { name: "unknown key in a cut config", files: &[("rec.csv", Text("time_s,fx_N\n0,1\n0.001,1\n")), ("cut.toml", Edit("identify/cut.toml", "teeth", "teeths"))],
          args: IDENTIFY, expect: &["cut.toml", "teeths"] },
    Row { name: "wrong unit in a cut config", files: &[("rec.csv", Text("time_s,fx_N\n0,1\n0.001,1\n")), ("cut.toml", Edit("identify/cut.toml", "diameter_mm = 10.0", "diameter_mm = \"10 kg\""))],
          args: IDENTIFY, expect: &["cut.toml", "diameter_mm", "kg"] },
    Row { name: "TOML syntax error", files: &[("rec.csv", Text("time_s,fx_N\n0,1\n0.001,1\n")), ("cut.toml", Text("teeth = 4\nrpm = = 3\n"))],
          args: IDENTIFY, expect: &["cut.toml", "line 2"] },
    Row { name: "FRF frequencies not increasing", files: &[("rec.csv", Example("identify/cut_fz0.05.txt")), CUT,
            ("frf.csv", Text("freq_Hz,xx_re,xx_im\n0,1,0\n10,1,0\n5,1,0\n"))],
          args: "identify {d}/rec.csv --config {d}/cut.toml --sensor-frf {d}/frf.csv --json {d}/id.json",
          expect: &["frf.csv:4", "strictly increasing"] },
    Row { name: "FRF without a frequency column", files: &[("rec.csv", Example("identify/cut_fz0.05.txt")), CUT,
            ("frf.csv", Text("f,xx_re,xx_im\n0,1,0\n"))],
          args: "identify {d}/rec.csv --config {d}/cut.toml --sensor-frf {d}/frf.csv --json {d}/id.json",
          expect: &["frf.csv:1", "freq_Hz"] },
    // ---- identify peaks / tests ----
    Row { name: "peak that is not a number", files: &[],
          args: "identify peaks --fz-mm 0.08 --ae-mm 2 --diameter-mm 10 --peaks-N 366,307,x,326 --json {d}/p.json",
          expect: &["--peaks-N", "`x`"] },
    Row { name: "negative peak", files: &[],
          args: "identify peaks --fz-mm 0.08 --ae-mm 2 --diameter-mm 10 --peaks-N 366,-307,259,326 --json {d}/p.json",
          expect: &["peaks_N[1]", ">= 0 N", "-307"] },
    Row { name: "teeth flag against the peaks", files: &[],
          args: "identify peaks --teeth 3 --fz-mm 0.08 --ae-mm 2 --diameter-mm 10 --peaks-N 366,307,259,326",
          expect: &["teeth", "3", "4"] },
    Row { name: "peak table cell not a number", files: &[("t.csv", Edit("seed003_table1.csv", "307.9", "3o7.9"))],
          args: "identify tests {d}/t.csv --json {d}/t.json", expect: &["t.csv:7", "3o7.9"] },
    Row { name: "JSON to stdout of a failing job", files: &[("t.csv", Edit("seed003_table1.csv", "up\n", "sideways\n"))],
          args: "identify tests {d}/t.csv --json -", expect: &["t.csv:", "sideways"] },
    Row { name: "peak table TOML syntax", files: &[("t.toml", Edit("seed003_table1.toml", "teeth = 4", "teeth = [4"))],
          args: "identify tests {d}/t.toml --json {d}/t.json", expect: &["t.toml:3", "comma"] },
    // ---- displacement ----
    Row { name: "readings without a reading column", files: &[("t.csv", Text("tooth,value\n0,1\n1,2\n2,3\n"))],
          args: "displacement teeth {d}/t.csv --teeth 3 --diameter-mm 0.5 --json {d}/o.json --plot {d}/o.svg",
          expect: &["t.csv", "reading_<unit>", "tooth, value"] },
    Row { name: "tooth number out of range", files: &[("t.csv", Text("tooth,reading_um\n0,1\n7,2\n2,3\n"))],
          args: "displacement teeth {d}/t.csv --teeth 3 --diameter-mm 0.5 --json {d}/o.json --plot {d}/o.svg",
          expect: &["t.csv:3", "column `tooth`", "tooth 7 is not in 0..3"] },
    Row { name: "a tooth without reading", files: &[("t.csv", Text("tooth,reading_um\n0,1\n1,2\n"))],
          args: "displacement teeth {d}/t.csv --teeth 3 --diameter-mm 0.5 --json {d}/o.json --plot {d}/o.svg",
          expect: &["t.csv", "no reading for tooth [2]"] },
    Row { name: "unknown sensor kind", files: &[("t.csv", Text("tooth,reading_um\n0,1\n1,2\n2,3\n"))],
          args: "displacement teeth {d}/t.csv --teeth 3 --diameter-mm 0.5 --sensor sideways --json {d}/o.json",
          expect: &["--sensor", "sideways"] },
    Row { name: "negative TIR", files: &[("h.csv", Text("z_mm,tir_um\n2,6\n5,-7\n8,8\n"))],
          args: "displacement heights {d}/h.csv --json {d}/o.json --plot {d}/o.svg",
          expect: &["h.csv:3", "column `tir_um`", "negative"] },
    Row { name: "decimal comma in a comma table", files: &[("h.csv", Text("z_mm,tir_um\n2,6\n5,7,5\n"))],
          args: "displacement heights {d}/h.csv --json {d}/o.json",
          expect: &["h.csv:3", "3 fields, expected 2"] },
    Row { name: "signal time not increasing", files: &[("s.csv", Text("time_s,disp_a_um\n0,1\n0.001,2\n0.001,3\n0.003,2\n"))],
          args: "displacement signal {d}/s.csv --json {d}/o.json --plot {d}/o.svg",
          expect: &["s.csv:4", "column `time_s`", "time does not increase"] },
    Row { name: "signal with a gap", files: &[("s.csv", Text("time_s,disp_a_um\n0,1\n0.001,2\n0.002,3\n0.009,2\n0.010,1\n"))],
          args: "displacement signal {d}/s.csv --json {d}/o.json",
          expect: &["s.csv:5", "evenly spaced"] },
    Row { name: "signal channel with a mass unit", files: &[("s.csv", Text("time_s,disp_a_kg\n0,1\n0.001,2\n"))],
          args: "displacement signal {d}/s.csv --json {d}/o.json",
          expect: &["s.csv", "disp_a_kg", "length unit"] },
    Row { name: "signal section past the end", files: &[("s.csv", Text(SIGNAL))],
          args: "displacement signal {d}/s.csv --from-s 5 --json {d}/o.json",
          expect: &["s.csv", "no sample in the selected section"] },
    // ---- chip: case files and toolpaths ----
    Row { name: "unknown key in a case file", files: &[("c.toml", Edit("chip/section2_5.toml", "helix_deg", "helix_degree"))],
          args: "chip compare {d}/c.toml --json {d}/c.json", expect: &["c.toml", "helix_degree"] },
    Row { name: "case file names a missing toolpath", files: &[("c.toml", Example("chip/flank_path.toml"))],
          args: "chip eval {d}/c.toml --out {d}/h.csv --json {d}/e.json", expect: &["flank.apt", "No such file"] },
    Row { name: "APT record not understood", files: &[("c.toml", Example("chip/flank_path.toml")),
            ("flank.apt", Edit("chip/flank.apt", "GOTO/-4.0000", "GOT0/-4.0000"))],
          args: "chip eval {d}/c.toml --out {d}/h.csv --json {d}/e.json", expect: &["flank.apt:13", "GOT0"] },
    Row { name: "joint table cell not a number", files: &[("c.toml", Example("chip/joints_no_rtcp.toml")),
            ("joints_no_rtcp.csv", Edit("chip/joints_no_rtcp.csv", "149.5", "149,5"))],
          args: "chip eval {d}/c.toml --out {d}/h.csv --json {d}/e.json", expect: &["joints_no_rtcp.csv:", "fields"] },
    Row { name: "unknown chip model", files: &[("c.toml", Example("chip/section2_5.toml"))],
          args: "chip eval {d}/c.toml --model parabolic --out {d}/h.csv", expect: &["--model", "parabolic"] },
    Row { name: "case file is a folder", files: &[("c.toml", Folder)],
          args: "chip compare {d}/c.toml --json {d}/c.json", expect: &["c.toml", "folder"] },
    Row { name: "plot into a missing folder after the table", files: &[("c.toml", Example("chip/section2_5.toml"))],
          args: "chip eval {d}/c.toml --out {d}/h.csv --json {d}/e.json --plot {d}/missing/p.svg",
          expect: &["missing/p.svg", "folder `{d}/missing` does not exist; create it or choose another path"] },
    // ---- grind: probe and edge tables, NC programs ----
    Row { name: "probe table with an unknown column", files: &[("probe.csv", Edit("grind/probe.csv", "angle_deg", "angle_grad")), EDGE],
          args: GRIND, expect: &["probe.csv:3: ", "unknown column `angle_grad`"] },
    Row { name: "probe cell not a number", files: &[("probe.csv", Edit("grind/probe.csv", "4.008611", "4.0O8611")), EDGE],
          args: GRIND, expect: &["probe.csv:4:", "`4.0O8611` in column `x_mm` is not a number"] },
    Row { name: "edge table without z", files: &[PROBE, ("edge.csv", Edit("grind/edge.csv", "x_mm,y_mm,z_mm", "x_mm,y_mm,w_mm"))],
          args: GRIND, expect: &["edge.csv", "w_mm"] },
    Row { name: "NC word without a number", files: &[PROBE, EDGE, ("flute.nc", Edit("grind/flute.nc", "N50 G1 X1.9176", "N50 G1 X"))],
          args: "grind compensate --probe {d}/probe.csv --bar-diameter-mm 6 --probe-tip-radius-mm 1 --edge {d}/edge.csv --nc {d}/flute.nc --out {d}/comp.nc --json {d}/g.json",
          expect: &["flute.nc", "line 7, column 8", "`X` has no number"] },
    Row { name: "NC output over the NC input", files: &[PROBE, EDGE, FLUTE],
          args: "grind compensate --probe {d}/probe.csv --bar-diameter-mm 6 --probe-tip-radius-mm 1 --edge {d}/edge.csv --nc {d}/flute.nc --out {d}/flute.nc",
          expect: &["flute.nc", "input"] },
    Row { name: "generatrix cell not a number", files: &[PROBE, EDGE, ("gen.csv", Text("u_mm,radius_mm\n0,3\n10,3.0.1\n"))],
          args: "grind compensate --probe {d}/probe.csv --generatrix {d}/gen.csv --probe-tip-radius-mm 1 --edge {d}/edge.csv --json {d}/g.json",
          expect: &["gen.csv", "line 3", "3.0.1"] },
    Row { name: "bar given twice", files: &[PROBE, EDGE, ("gen.csv", Text("u_mm,radius_mm\n0,3\n10,3\n"))],
          args: "grind compensate --probe {d}/probe.csv --generatrix {d}/gen.csv --bar-diameter-mm 6 --edge {d}/edge.csv --json {d}/g.json",
          expect: &["--bar-diameter-mm", "--generatrix", "not both"] },
    // ---- shank ----
    Row { name: "shank config without the modulus", files: &[("shank.toml", Text("[shank]\ndiameter_mm = 8\n")), SHANK_REC],
          args: "shank force {d}/rec.csv --config {d}/shank.toml --json {d}/s.json --out {d}/f.csv --plot-dir {d}/plots",
          expect: &["shank.toml", "modulus_gpa"] },
    Row { name: "shank sensors in the wrong order", files: &[("shank.toml", Edit("shank.toml", "l1_mm = 10", "l1_mm = 40")), SHANK_REC],
          args: "shank force {d}/rec.csv --config {d}/shank.toml --json {d}/s.json --out {d}/f.csv",
          expect: &["shank.toml", "l1_mm"] },
    Row { name: "shank recording without a sensor channel", files: &[SHANK_CFG, ("rec.csv", Text("time_s,xI_um,yI_um,yII_um\n0,0,0,0\n0.00005,0,0,0\n"))],
          args: "shank force {d}/rec.csv --config {d}/shank.toml --json {d}/s.json --out {d}/f.csv",
          expect: &["xII"] },
    Row { name: "shank FRF table with a text cell", files: &[("shank.toml", Edit("shank.toml", "[processing]", "[dynamics]\nfrf = \"frf.csv\"\n\n[processing]")), SHANK_REC,
            ("frf.csv", Text("freq_Hz,xx_re,xx_im,yy_re,yy_im\n0,1,0,1,0\n100,1,zero,1,0\n"))],
          args: "shank force {d}/rec.csv --config {d}/shank.toml --json {d}/s.json --out {d}/f.csv",
          expect: &["frf.csv:3", "`zero`", "xx_im"] },
    Row { name: "calibration load channel missing", files: &[SHANK_CFG, SHANK_REC],
          args: "shank calibrate {d}/rec.csv --config {d}/shank.toml --force-channel load_N --load-point-mm 60 --json {d}/c.json",
          expect: &["load_N"] },
    Row { name: "zero shank diameter", files: &[],
          args: "shank stiffness --modulus-gpa 210 --diameter-mm 0 --tool-length-mm 65 --l1-mm 10 --l2-mm 30 --json {d}/k.json",
          expect: &["diameter_mm", "got 0"] },
    // ---- simulate ----
    Row { name: "zero teeth", files: &[], args: "simulate --teeth 0 --diameter-mm 10 --rpm 3240 --fz-mm 0.08 --ap-mm 1 --ae-mm 2 --mode down --ktc 1889.2 --krc 806.1 --json {d}/sim.json",
          expect: &["--teeth (key `teeth`): expected an integer in [1, 360]", "got 0"] },
    Row { name: "unknown milling mode", files: &[], args: "simulate --teeth 4 --diameter-mm 10 --rpm 3240 --fz-mm 0.08 --ap-mm 1 --ae-mm 2 --mode sideways --ktc 1889.2 --krc 806.1 --json {d}/sim.json",
          expect: &["mode", "sideways"] },
    Row { name: "case config with a non-finite value", files: &[("case.toml", Edit("simulate.toml", "rpm = 3240.0", "rpm = nan"))],
          args: "simulate {d}/case.toml --json {d}/sim.json --out {d}/forces.csv", expect: &["case.toml", "rpm"] },
    Row { name: "JSON over the case config", files: &[("case.toml", Example("simulate.toml"))],
          args: "simulate {d}/case.toml --json {d}/case.toml", expect: &["case.toml", "input"] },
    Row { name: "CSV into a missing folder with JSON and plot", files: &[], args: "SIM --out {d}/no/forces.csv --json {d}/sim.json --plot {d}/forces.svg",
          expect: &["no/forces.csv", "No such file or directory (os error 2); check the path"] },
    Row { name: "plot onto a folder", files: &[("plot.svg", Folder)], args: "SIM --json {d}/sim.json --plot {d}/plot.svg",
          expect: &["plot.svg", "is a folder"] },
    Row { name: "sensor FRF that is a folder", files: &[("frf.csv", Folder)],
          args: "SIM SIM_OUT --recording {d}/rec.csv --sample-rate-hz 20000 --sensor-frf {d}/frf.csv",
          expect: &["frf.csv", "folder"] },
];

fn example(path: &str) -> PathBuf {
    common::example(path)
}

/// Every file and folder under `dir` (relative paths) with a hash of each file's bytes.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Option<u64>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(dir).unwrap().to_path_buf();
            if p.is_dir() {
                out.insert(rel, None);
                stack.push(p);
            } else {
                let mut h = DefaultHasher::new();
                std::fs::read(&p).unwrap().hash(&mut h);
                out.insert(rel, Some(h.finish()));
            }
        }
    }
    out
}

fn write_inputs(dir: &Path, files: &[(&str, Src)]) {
    for (name, src) in files {
        let p = dir.join(name);
        match src {
            Text(t) => std::fs::write(&p, t).unwrap(),
            Bytes(b) => std::fs::write(&p, b).unwrap(),
            Example(e) => {
                std::fs::copy(example(e), &p).unwrap();
            }
            Edit(e, from, to) => {
                // shank.toml lives with the CLI tests, the others under examples/
                let text = match *e {
                    "shank.toml" => SHANK_TOML.to_string(),
                    _ => std::fs::read_to_string(example(e)).unwrap(),
                };
                assert!(text.contains(from), "{name}: `{from}` not in {e}");
                std::fs::write(&p, text.replacen(from, to, 1)).unwrap();
            }
            Folder => std::fs::create_dir(&p).unwrap(),
        }
    }
}

/// The problems of one row (empty when it passes).
/// Issue 21 item 4: messages in the user's words — no module paths (`identify::full_signal`), no
/// Debug spellings (`Some(…)`, `Foo { … }`, `[1.0, 2.0]` from `{:?}`), no citation of a file the user
/// does not have (the spec is cited as `docs/methods.md`, which ships with the sources).
fn words_from_the_code(message: &str) -> Vec<String> {
    let mut found = Vec::new();
    for token in [
        "::",
        "Some(",
        "None",
        "Ok(",
        "Err(",
        " { ",
        "\\\"",
        "ParamError",
        "Error {",
    ] {
        if message.contains(token) {
            found.push(token.to_string());
        }
    }
    let bare_spec = message
        .match_indices("methods.md")
        .any(|(i, _)| !message[..i].ends_with("docs/"));
    if bare_spec {
        found.push("methods.md without docs/".into());
    }
    found
}

fn check(row: &Row) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_inputs(d, row.files);
    let before = snapshot(d);
    let line = row.args.replace("SIM_OUT", SIM_OUT).replace("SIM", SIM);
    let args: Vec<String> = line
        .split_whitespace()
        .map(|a| a.replace("{d}", d.to_str().unwrap()))
        .collect();
    let out = runout().args(&args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).replace(d.to_str().unwrap(), "{d}");
    let mut problems = Vec::new();
    if out.status.code() != Some(1) {
        problems.push(format!("exit {:?}", out.status.code()));
    }
    if !out.stdout.is_empty() {
        problems.push(format!(
            "printed to stdout: {}",
            String::from_utf8_lossy(&out.stdout)
        ));
    }
    if err.contains("panicked") || !err.starts_with("error: ") {
        problems.push("not a plain `error: …` message".into());
    }
    for w in words_from_the_code(&err) {
        problems.push(format!("words from the code: `{w}`"));
    }
    for w in row.expect {
        if !err.contains(w) {
            problems.push(format!("`{w}` not in the message"));
        }
    }
    let first = err.lines().next().unwrap_or("");
    let parts: Vec<&str> = first.split(": ").filter(|p| p.len() > 12).collect();
    for (i, p) in parts.iter().enumerate() {
        if parts[..i].contains(p) {
            problems.push(format!("`{p}` printed twice"));
        }
    }
    let after = snapshot(d);
    for (p, h) in &before {
        match after.get(p) {
            Some(a) if a == h => {}
            Some(_) => problems.push(format!("input {} changed", p.display())),
            None => problems.push(format!("input {} removed", p.display())),
        }
    }
    for p in after.keys().filter(|p| !before.contains_key(*p)) {
        problems.push(format!("left behind: {}", p.display()));
    }
    if problems.is_empty() {
        Vec::new()
    } else {
        vec![format!(
            "row `{}`: {}\n    runout {}\n    {}",
            row.name,
            problems.join("; "),
            line,
            err.trim_end().replace('\n', "\n    ")
        )]
    }
}

#[test]
fn bad_inputs_are_refused_clearly_and_leave_nothing_behind() {
    assert!(ROWS.len() >= 40, "issue 14 asks for at least 40 rows");
    let failures: Vec<String> = ROWS.iter().flat_map(check).collect();
    assert!(
        failures.is_empty(),
        "{} of {} rows failed:\n{}",
        failures.len(),
        ROWS.len(),
        failures.join("\n")
    );
}

/// The harness itself: a good command passes the "nothing left behind" check only because its
/// outputs are listed — it does write them, so a failing row that wrote would be caught.
#[test]
fn a_successful_command_does_write_its_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let line = format!("{SIM} {SIM_OUT}").replace("{d}", d);
    runout().args(line.split_whitespace()).success_output();
    let files = snapshot(dir.path());
    for f in ["forces.csv", "sim.json", "forces.svg"] {
        assert!(
            files.contains_key(Path::new(f)),
            "{f} not written: {files:?}"
        );
    }
}

/// Issue 14 item 5: an error ends with what the user can do, where that is known. A sample of
/// the rows above with the end of their message.
#[test]
fn errors_end_with_what_to_do() {
    let hints: &[(&str, &str)] = &[
        ("recording is a folder", "expected a file, got a folder"),
        (
            "recording does not exist",
            "check the path (relative paths start at the current folder)",
        ),
        ("case file is a folder", "is a folder: expected a file"),
        (
            "readings without a reading column",
            "the header has tooth, value",
        ),
        (
            "no time column and no rate",
            "(see `runout identify --help`)",
        ),
        (
            "peak that is not a number",
            "(see `runout identify peaks --help`)",
        ),
        (
            "unknown sensor kind",
            "(see `runout displacement teeth --help`)",
        ),
        (
            "signal section past the end",
            "inside them\n  (see `runout displacement signal --help`)",
        ),
        ("bar given twice", "(see `runout grind compensate --help`)"),
        ("unknown chip model", "(see `runout chip eval --help`)"),
    ];
    for (name, hint) in hints {
        let row = ROWS.iter().find(|r| r.name == *name).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        write_inputs(d, row.files);
        let line = row.args.replace("SIM_OUT", SIM_OUT).replace("SIM", SIM);
        let args: Vec<String> = line
            .split_whitespace()
            .map(|a| a.replace("{d}", d.to_str().unwrap()))
            .collect();
        let out = runout().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.trim_end().ends_with(hint), "{name}: {err}");
    }
    // the flag hint names the command as typed, also after positional arguments
    let out = runout()
        .args(["identify", "peaks", "--fz-mm", "x", "--peaks-N", "1,2"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("error: --fz-mm")
            && err
                .trim_end()
                .ends_with("(see `runout identify peaks --help`)"),
        "{err}"
    );
}

#[test]
fn the_words_from_the_code_check_catches_them() {
    assert_eq!(
        words_from_the_code("error: identify::full_signal failed"),
        ["::"]
    );
    assert_eq!(words_from_the_code("value Some(3.0)"), ["Some("]);
    assert_eq!(
        words_from_the_code("see methods.md §4.2"),
        ["methods.md without docs/"]
    );
    assert!(words_from_the_code("see docs/methods.md §4.2 and pass --helix-deg").is_empty());
}
