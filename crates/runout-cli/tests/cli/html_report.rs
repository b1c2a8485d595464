//! The engineer's HTML report (issue 15): `--html` of the jobs and `runout report JSON…`.
//!
//! Checked on the page text: one self-contained document (no script, no URL but the SVG
//! namespace, balanced elements), the verdict present, every number carrying `data-key` equal to
//! the JSON's value at that pointer (the page shows the report's numbers, not recomputed ones),
//! and every plot present as inline SVG. The same page rendered by headless Chromium (no console
//! error, the verdict and plots in the DOM, a screenshot) is the ignored test at the end.

use crate::common;
use common::{example, runout, Ran, IDENTIFY_EXAMPLE_INPUTS};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Run `runout ARGS` from the repository root (identify needs one thread for identical results).
fn run(args: &[&str]) {
    let out = runout()
        .current_dir(example(".."))
        .env("RAYON_NUM_THREADS", "1")
        .args(args)
        .output()
        .unwrap();
    // 3: ran, not (fully) identified (the 3-tooth readings without an SE): the outputs are
    // written all the same (issue 21)
    assert!(
        matches!(out.status.code(), Some(0 | 3)),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `(data-key, data-value)` of the `n`-th section (`None`: the whole page).
fn keyed(html: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (at, _) in html.match_indices("data-key=\"") {
        let rest = &html[at + 10..];
        let key = &rest[..rest.find('"').unwrap()];
        let rest = &rest[key.len()..];
        let v = rest
            .strip_prefix("\" data-value=\"")
            .expect("value follows key");
        let value = &v[..v.find('"').unwrap()];
        out.push((key.to_string(), value.to_string()));
    }
    out
}

/// The report's sections (`<section class="report" …> … </section>`).
fn sections(html: &str) -> Vec<&str> {
    html.split("<section class=\"report\"").skip(1).collect()
}

/// Self-contained, well-formed enough: doctype, no script, no external resource, every
/// non-void element closed in order.
fn check_document(html: &str) {
    assert!(html.starts_with("<!DOCTYPE html>"));
    let lower = html.to_lowercase();
    assert!(!lower.contains("<script"), "a script in the page");
    for bad in ["<link", "@import", "url(", "<img", "<iframe"] {
        assert!(!lower.contains(bad), "external resource `{bad}`");
    }
    let urls: Vec<&str> = lower
        .match_indices("http")
        .map(|(i, _)| &lower[i..(i + 30).min(lower.len())])
        .filter(|u| u.starts_with("http://") || u.starts_with("https://"))
        .filter(|u| !u.starts_with("http://www.w3.org/2000/svg"))
        .collect();
    // the tolerance source cites a web page as text, never as a resource to load
    assert!(
        urls.iter().all(|u| !lower.contains(&format!("src=\"{u}"))),
        "{urls:?}"
    );
    // element balance (void elements and self-closed SVG elements excepted)
    let void = ["meta", "br", "hr", "img", "input", "link"];
    let mut stack: Vec<String> = Vec::new();
    let mut rest = html;
    while let Some(i) = rest.find('<') {
        rest = &rest[i + 1..];
        let end = rest.find('>').expect("tag closed");
        let tag = &rest[..end];
        rest = &rest[end + 1..];
        if tag.starts_with('!') || tag.starts_with('?') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            let open = stack.pop().unwrap_or_default();
            assert_eq!(open, name.trim(), "closing </{name}> after <{open}>");
            continue;
        }
        let name: String = tag
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
            .collect();
        if tag.ends_with('/') || void.contains(&name.as_str()) {
            continue;
        }
        stack.push(name);
    }
    assert!(stack.is_empty(), "unclosed elements {stack:?}");
}

/// Every keyed number of `section` equals the JSON's value at its pointer.
fn check_numbers(section: &str, json: &Value) -> usize {
    let pairs = keyed(section);
    for (k, v) in &pairs {
        let want = json
            .pointer(k)
            .unwrap_or_else(|| panic!("{k} not in the JSON"));
        match want {
            Value::Number(n) => {
                // the page writes the JSON's shortest round-trip digits; `shown` is parsed
                // exactly by std, the JSON by serde_json's fast parser (without its
                // `float_roundtrip` feature it may be 1 ulp off): equal to 2 ulp
                let shown: f64 = v.parse().unwrap_or_else(|_| panic!("{k}: `{v}`"));
                let want = n.as_f64().unwrap();
                assert!(
                    (shown - want).abs() <= 2.0 * f64::EPSILON * want.abs(),
                    "{k}: page {shown}, JSON {want}"
                );
            }
            Value::String(s) => assert_eq!(s, v, "{k}"),
            o => panic!("{k}: unexpected {o}"),
        }
    }
    pairs.len()
}

fn read_json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// The bundled example (the README's main job) with `--html`.
fn identify_example(dir: &Path) -> (PathBuf, PathBuf) {
    let (h, j) = (dir.join("identify.html"), dir.join("identify.json"));
    let mut args = IDENTIFY_EXAMPLE_INPUTS.to_vec();
    args.extend(["--json", j.to_str().unwrap(), "--html", h.to_str().unwrap()]);
    run(&args);
    (h, j)
}

#[test]
fn identify_example_page_shows_the_reports_numbers_verdict_and_plots() {
    let d = tempfile::tempdir().unwrap();
    let (h, j) = identify_example(d.path());
    let html = std::fs::read_to_string(&h).unwrap();
    let json = read_json(&j);
    check_document(&html);
    let s = sections(&html);
    assert_eq!(s.len(), 1);
    let n = check_numbers(s[0], &json);
    assert!(n > 60, "only {n} numbers keyed");
    // the verdict: the example has 8 µm runout (TIR 16 µm > 10 µm for D = 10 mm)
    assert_eq!(json["verdict"]["status"], "fail");
    assert!(html.contains(
        "<div class=\"status\" data-key=\"/verdict/status\" data-value=\"fail\">FAIL</div>"
    ));
    // the runout and its SE are shown and equal the JSON (checked above); and the verdict table
    for k in [
        "/full_signal/offset_um",
        "/full_signal/offset_um_se",
        "/full_signal/angle_deg",
        "/verdict/teeth/3/load_share",
        "/full_signal/coefficients/ktc_N_per_mm2_se",
    ] {
        assert!(keyed(s[0]).iter().any(|(key, _)| key == k), "{k} not shown");
    }
    // every plot: polar, and per recording the waveform and the per-tooth peaks
    for p in [
        "polar",
        "waveform_0",
        "waveform_1",
        "tooth_peaks_0",
        "tooth_peaks_1",
    ] {
        let at = html
            .find(&format!("data-plot=\"{p}\""))
            .unwrap_or_else(|| panic!("plot {p} missing"));
        assert!(html[at..].trim_start_matches(|c| c != '>')[1..]
            .trim_start()
            .starts_with("<svg"));
    }
}

#[test]
fn displacement_pages_and_the_comparison_of_saved_reports() {
    let d = tempfile::tempdir().unwrap();
    let mut jsons = Vec::new();
    // two tools: the seed-000 case (ρ 5 µm) and a worse one
    for (name, rows) in [
        (
            "a",
            "seed_edge,reading_um\n1,253.850568\n2,250.916561\n3,245.307498\n",
        ),
        ("b", "seed_edge,reading_um\n1,256.0\n2,250.9\n3,243.3\n"),
    ] {
        let csv = d.path().join(format!("{name}.csv"));
        std::fs::write(&csv, rows).unwrap();
        let (j, h) = (
            d.path().join(format!("{name}.json")),
            d.path().join(format!("{name}.html")),
        );
        run(&[
            "displacement",
            "teeth",
            csv.to_str().unwrap(),
            "--teeth",
            "3",
            "--diameter-mm",
            "0.5",
            "--sensor",
            "radial",
            "--fz-mm",
            "0.002",
            "--tolerance-um",
            "12",
            "--json",
            j.to_str().unwrap(),
            "--html",
            h.to_str().unwrap(),
        ]);
        let html = std::fs::read_to_string(&h).unwrap();
        check_document(&html);
        let json = read_json(&j);
        assert_eq!(json["verdict"]["tolerance_tir_um"], 12.0);
        assert!(check_numbers(sections(&html)[0], &json) > 20);
        assert!(html.contains("data-plot=\"polar\""));
        jsons.push(j);
    }
    // both saved reports in one page, judged again against 8 µm: a comparison table
    let page = d.path().join("both.html");
    run(&[
        "report",
        jsons[0].to_str().unwrap(),
        jsons[1].to_str().unwrap(),
        "--tolerance-um",
        "8",
        "--html",
        page.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(&page).unwrap();
    check_document(&html);
    let table = &html[html.find("id=\"comparison-table\"").expect("comparison")..];
    let table = &table[..table.find("</table>").unwrap()];
    assert_eq!(table.matches("<tr>").count(), 3, "head + 2 rows");
    assert!(table.contains("FAIL"));
    assert_eq!(
        table
            .matches("data-key=\"/verdict/tolerance_tir_um\" data-value=\"8.0\"")
            .count(),
        2,
        "both judged against 8 µm"
    );
    let s = sections(&html);
    assert_eq!(s.len(), 2);
    for (sec, j) in s.iter().zip(&jsons) {
        let mut json = read_json(j);
        // judged again: the page's verdict is the 8 µm one, the rest as saved
        assert!(sec.contains("the tolerance 8.0 µm TIR (given)"));
        let status = if sec.contains("data-value=\"fail\"") {
            "fail"
        } else {
            "pass"
        };
        json["verdict"]["status"] = status.into();
        check_numbers(sec, &json);
    }
    // a report of another kind is refused with the schemas it knows
    let bad = d.path().join("x.json");
    std::fs::write(&bad, "{\"schema\": \"runout.simulate/1\"}").unwrap();
    let out = runout()
        .args(["report", bad.to_str().unwrap(), "--html", "-"])
        .failure_output();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("x.json: schema `runout.simulate/1` has no HTML page"),
        "{e}"
    );
}

/// Issue 15 item 1: a saved **identify** report in `runout report`, next to a displacement one:
/// the comparison table has both rows (holder A vs B), the identify section shows the answer with
/// the JSON's numbers and the verdict judged again at the given tolerance.
#[test]
fn saved_identify_report_in_the_comparison_page() {
    let d = tempfile::tempdir().unwrap();
    let (_, id_json) = identify_example(d.path());
    let teeth = d.path().join("teeth.json");
    run(&[
        "displacement",
        "teeth",
        "examples/displacement/teeth.csv",
        "--teeth",
        "4",
        "--diameter-mm",
        "10",
        "--helix-deg",
        "30",
        "--json",
        teeth.to_str().unwrap(),
    ]);
    let page = d.path().join("both.html");
    run(&[
        "report",
        id_json.to_str().unwrap(),
        teeth.to_str().unwrap(),
        "--tolerance-um",
        "20",
        "--html",
        page.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(&page).unwrap();
    check_document(&html);
    let table = &html[html.find("id=\"comparison-table\"").expect("comparison")..];
    let table = &table[..table.find("</table>").unwrap()];
    assert_eq!(table.matches("<tr>").count(), 3, "head + 2 rows");
    assert_eq!(
        table
            .matches("data-key=\"/verdict/tolerance_tir_um\" data-value=\"20.0\"")
            .count(),
        2
    );
    let json = read_json(&id_json);
    let s = sections(&html);
    assert!(
        s[0].contains("The answer") && s[0].contains("identified"),
        "{}",
        s[0]
    );
    // the answer's numbers equal the JSON's (the verdict is judged again: 2ρ 15.95 µm < 20 µm)
    let answer: Vec<(String, String)> = keyed(s[0])
        .into_iter()
        .filter(|(k, _)| k.starts_with("/answer/"))
        .collect();
    assert_eq!(answer.len(), 4, "{answer:?}");
    for (k, v) in answer {
        let want = json.pointer(&k).unwrap().as_f64().unwrap();
        let shown: f64 = v.parse().unwrap();
        assert!(
            (shown - want).abs() <= 2.0 * f64::EPSILON * want.abs(),
            "{k}"
        );
    }
    assert!(s[0].contains("the tolerance 20.0 µm TIR (given)"));
    assert!(s[0].contains("data-value=\"pass\""));
}

/// Headless Chromium renders the example's page: no console error, the verdict and every plot
/// in the rendered DOM, numbers in the DOM equal to the JSON's, and a PNG screenshot.
#[test]
#[ignore = "needs chromium (Debian package `chromium`; .ci/run installs it)"]
fn chromium_renders_the_example_report() {
    use std::process::Command;
    let d = tempfile::tempdir().unwrap();
    let (h, j) = identify_example(d.path());
    let url = format!("file://{}", h.display());
    let base = |c: &mut Command| {
        c.args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--enable-logging=stderr",
            "--v=0",
        ]);
    };
    let mut dump = Command::new("chromium");
    base(&mut dump);
    let out = dump
        .args(["--dump-dom", &url])
        .output()
        .expect("chromium runs");
    assert!(out.status.success());
    let dom = String::from_utf8(out.stdout).unwrap();
    let log = String::from_utf8_lossy(&out.stderr);
    // page errors reach the log as CONSOLE lines (dbus/GPU noise of a headless box does not)
    for l in log.lines() {
        assert!(
            !(l.contains("CONSOLE") || l.contains("Uncaught") || l.contains("ERR_FILE_NOT_FOUND")),
            "console error: {l}"
        );
    }
    let json = read_json(&j);
    let s = sections(&dom);
    assert_eq!(s.len(), 1, "the DOM has the report section");
    assert!(check_numbers(s[0], &json) > 60);
    assert!(dom.contains(">FAIL</div>"));
    assert_eq!(dom.matches("data-plot=").count(), 5, "every plot rendered");
    assert!(dom.matches("<svg").count() >= 5);
    let png = d.path().join("page.png");
    let mut shot = Command::new("chromium");
    base(&mut shot);
    let out = shot
        .args([
            &format!("--screenshot={}", png.display()),
            "--window-size=1100,2600",
            &url,
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let bytes = std::fs::read(&png).unwrap();
    assert!(
        bytes.starts_with(b"\x89PNG") && bytes.len() > 50_000,
        "{} bytes",
        bytes.len()
    );
}
