//! Readers of the displacement tables: unit conversion by header, seed edge mapping, and errors
//! that name the file, line and column.

use runout_io::displacement::*;
use std::io::Write;
use std::path::PathBuf;

fn file(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::File::create(&p)
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    p
}

#[test]
fn tooth_table_units_and_numbering() {
    let d = tempfile::tempdir().unwrap();
    let p = file(
        &d,
        "t.csv",
        "# laser readings\ntooth,reading_um\n0, 12.5\n1,10\n2,8\n0,12.7\n",
    );
    let t = read_tooth_table(&p, 3).unwrap();
    assert_eq!(t.readings.len(), 4);
    assert!((t.readings[0].1 - 0.0125).abs() < 1e-15);
    assert!(!t.from_seed_edges);
    // seed edges: k = 2 of K = 4 is our tooth 3
    let p = file(
        &d,
        "s.csv",
        "seed_edge,reading_mm\n1,0.1\n2,0.2\n3,0.3\n4,0.4\n",
    );
    let t = read_tooth_table(&p, 4).unwrap();
    assert_eq!(t.readings[1], (3, 0.2));
    assert!(t.from_seed_edges);
}

#[test]
fn tooth_table_errors_name_file_line_column() {
    let d = tempfile::tempdir().unwrap();
    let p = file(&d, "bad.csv", "tooth,reading_um\n0,1\n1,abc\n");
    let e = read_tooth_table(&p, 2).unwrap_err().to_string();
    assert!(
        e.contains("bad.csv:3:2: `abc` in column `reading_um` is not a number"),
        "{e}"
    );
    let p = file(&d, "nan.csv", "tooth,reading_um\n0,NaN\n");
    let e = read_tooth_table(&p, 2).unwrap_err().to_string();
    assert!(e.contains("nan.csv:2") && e.contains("finite"), "{e}");
    let p = file(&d, "range.csv", "tooth,reading_um\n0,1\n5,1\n");
    let e = read_tooth_table(&p, 2).unwrap_err().to_string();
    assert!(
        e.contains("range.csv:3:1: column `tooth`") && e.contains("0..2"),
        "{e}"
    );
    let p = file(&d, "unit.csv", "tooth,reading_rpm\n0,1\n");
    let e = read_tooth_table(&p, 2).unwrap_err().to_string();
    assert!(
        e.contains("unit.csv: header") && e.contains("reading_rpm"),
        "{e}"
    );
    let p = file(&d, "nocol.csv", "tooth,value\n0,1\n");
    let e = read_tooth_table(&p, 2).unwrap_err().to_string();
    assert!(e.contains("reading_<unit>"), "{e}");
    let p = file(&d, "short.csv", "tooth,reading_um\n0,1\n1\n");
    let e = read_tooth_table(&p, 2).unwrap_err().to_string();
    assert!(e.contains("short.csv:3"), "{e}");
    let e = read_tooth_table(&d.path().join("missing.csv"), 2)
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.csv"), "{e}");
}

#[test]
fn height_table() {
    let d = tempfile::tempdir().unwrap();
    let p = file(&d, "h.csv", "z_mm,tir_um,angle_deg\n10,8,30\n20,10,40\n");
    let h = read_height_table(&p).unwrap();
    assert!((h[0].runout_mm - 0.004).abs() < 1e-15); // TIR/2
    assert!((h[1].angle_rad.unwrap() - 40f64.to_radians()).abs() < 1e-15);
    let p = file(&d, "r.csv", "z_um,runout_mm\n1000,0.004\n");
    let h = read_height_table(&p).unwrap();
    assert_eq!(
        (h[0].z_mm, h[0].runout_mm, h[0].angle_rad),
        (1.0, 0.004, None)
    );
    let p = file(&d, "neg.csv", "z_mm,tir_um\n1,-3\n");
    let e = read_height_table(&p).unwrap_err().to_string();
    assert!(
        e.contains("neg.csv:2:2: column `tir_um`") && e.contains("negative"),
        "{e}"
    );
}

#[test]
fn signal_table() {
    let d = tempfile::tempdir().unwrap();
    let mut s = String::from("time_ms,disp_a_um,disp_b_mm,pulse\n");
    for i in 0..10 {
        s += &format!(
            "{},{},{},{}\n",
            i as f64 * 0.02,
            i,
            0.001 * i as f64,
            (i % 5 == 0) as u8
        );
    }
    let p = file(&d, "s.csv", &s);
    let t = read_signal(&p, &SignalSection::default()).unwrap();
    assert!((t.sample_rate_hz - 50_000.0).abs() < 1e-6);
    assert_eq!(t.channels[0].0, "a");
    assert_eq!(t.channels[1].0, "b");
    assert!(
        (t.channels[0].1[3] - 0.003).abs() < 1e-15 && (t.channels[1].1[3] - 0.003).abs() < 1e-15
    );
    assert_eq!(t.pulse.as_ref().unwrap()[5], 1.0);
    // a gap in time
    let p = file(
        &d,
        "gap.csv",
        "time_s,disp_a_um\n0,1\n0.1,1\n0.2,1\n0.5,1\n0.6,1\n",
    );
    let e = read_signal(&p, &SignalSection::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("gap.csv:") && e.contains("time_s") && e.contains("grid"),
        "{e}"
    );
    // no displacement channel
    let p = file(&d, "none.csv", "time_s,pulse\n0,1\n0.1,0\n");
    let e = read_signal(&p, &SignalSection::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("disp_<name>_<unit>"), "{e}");
}

#[test]
fn signal_section_and_sample_cap() {
    // 1 000 samples at 1 kHz (time in ms); the gap after 0.8 s lies outside the section
    let d = tempfile::tempdir().unwrap();
    let mut s = String::from("time_ms,disp_a_um\n");
    for i in 0..1000 {
        let t_ms = if i < 800 { i as f64 } else { i as f64 + 50.0 };
        s += &format!("{t_ms},{}\n", i % 7);
    }
    let p = file(&d, "long.csv", &s);
    let sec = SignalSection {
        from_s: Some(0.1),
        to_s: Some(0.3995),
        ..Default::default()
    };
    let t = read_signal(&p, &sec).unwrap();
    assert_eq!(t.channels[0].1.len(), 300); // 100 ms … 399 ms
    assert!((t.start_s - 0.1).abs() < 1e-12);
    assert!((t.channels[0].1[0] - 100.0 % 7.0 * 1e-3).abs() < 1e-15);
    // the whole file has the gap: refused with its line (header = line 1, sample i = line i + 2)
    let e = read_signal(&p, &SignalSection::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("long.csv:802") && e.contains("grid"), "{e}");
    // the cap names the line where it is exceeded and how to select less
    let cap = SignalSection {
        max_samples: 250,
        ..Default::default()
    };
    let e = read_signal(&p, &cap).unwrap_err().to_string();
    assert!(e.contains("long.csv:252") && e.contains("--from-s"), "{e}");
    // time going back names its line
    let p2 = file(
        &d,
        "back.csv",
        "time_s,disp_a_um\n0,1\n0.1,1\n0.2,1\n0.15,1\n0.3,1\n",
    );
    let e = read_signal(&p2, &SignalSection::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("back.csv:5") && e.contains("does not increase"),
        "{e}"
    );
    // an empty section
    let none = SignalSection {
        from_s: Some(5.0),
        ..Default::default()
    };
    let e = read_signal(&p, &none).unwrap_err().to_string();
    assert!(e.contains("no sample in the selected section"), "{e}");
}
