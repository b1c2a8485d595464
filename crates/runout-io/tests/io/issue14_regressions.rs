//! Issue 14: what the mutated-input property tests (`mutated_inputs.rs`) found, one regression
//! test each. (The fuzz targets found no crash or hang; see README "Fuzzing".)

use runout_io::displacement::{read_height_table, read_signal, SignalSection};
use runout_io::frf::parse_frf;
use runout_io::grind::read_probe_csv;

/// An FRF error about the whole file said `frf.csv:0:`; there is no line 0.
#[test]
fn frf_error_without_a_line_names_no_line_zero() {
    let e = parse_frf("frf.csv", "").unwrap_err();
    assert_eq!(e.line, 0);
    assert!(e.to_string().starts_with("frf.csv: empty"), "{e}");
    let e = parse_frf("frf.csv", "# c\nfreq_Hz,xx_re\n").unwrap_err();
    assert!(e.to_string().starts_with("frf.csv:2: "), "{e}");
}

/// A quoted header cell with line breaks (a mutated signal file) put the whole file into the
/// message; names are now quoted: at most 80 characters, control characters escaped.
#[test]
fn header_names_in_messages_are_short_and_on_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("h.csv");
    let long: String = (0..200).map(|i| format!("{i},{i}\n")).collect();
    std::fs::write(&p, format!("z_mm,\"tir\n{long}\"\n1,2\n")).unwrap();
    let e = read_height_table(&p).unwrap_err().to_string();
    assert!(e.lines().count() == 1 && e.len() < 400, "{e}");
    assert!(e.contains("the header has z_mm, tir\\n0,0\\n"), "{e}");
    let probe = format!("layer,\"u_mm\n{long}\",angle_deg\n0,1,2\n");
    let e = read_probe_csv(&probe, "probe.csv").unwrap_err().to_string();
    assert!(e.lines().count() == 1 && e.len() < 400, "{e}");
    // an FRF table whose comment lost its `#` and opens a quoted field that runs to the end
    // (found by the mutated-inputs proptest in CI): the header is quoted, cut at 80 characters
    let frf = format!("\" impact test, tool tip\nfreq_Hz, xx_re, xx_im, yy_re, yy_im\n{long}");
    let e = parse_frf("frf.csv", &frf).unwrap_err().to_string();
    assert!(e.lines().count() == 1 && e.len() < 400, "{e}");
    assert!(e.contains("no `freq_Hz` column"), "{e}");
}

/// The header of a grind table after comment lines was reported on line 1.
#[test]
fn grind_header_line_counts_comment_lines() {
    let e = read_probe_csv("# probe\n# more\nlayer,u_mm,angle_grad\n0,1,2\n", "p.csv")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("p.csv:3: unknown column `angle_grad`"), "{e}");
}

/// A gap in a raw signal was reported at the first sample (its step differed from the mean
/// step, which the gap itself inflates); it is reported where it is.
#[test]
fn a_signal_gap_is_reported_where_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.csv");
    std::fs::write(
        &p,
        "time_s,disp_a_um\n0,1\n0.001,2\n0.002,3\n0.009,2\n0.010,1\n",
    )
    .unwrap();
    let e = read_signal(&p, &SignalSection::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("s.csv:5: column `time_s`: time step 7.000000e-3 s"),
        "{e}"
    );
    // evenly spaced with jitter well under half a step still reads
    let rows: String = (0..50)
        .map(|i| {
            format!(
                "{},{i}\n",
                i as f64 * 1e-3 + if i % 2 == 0 { 1e-5 } else { 0.0 }
            )
        })
        .collect();
    std::fs::write(&p, format!("time_s,disp_a_um\n{rows}")).unwrap();
    let s = read_signal(&p, &SignalSection::default()).unwrap();
    assert!((s.sample_rate_hz - 1000.0).abs() < 1.0);
}

/// A section with no sample says where the signal's times are.
#[test]
fn an_empty_section_gives_the_time_range() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.csv");
    std::fs::write(&p, "time_s,disp_a_um\n0,1\n0.001,2\n0.002,3\n").unwrap();
    let section = SignalSection {
        from_s: Some(5.0),
        ..Default::default()
    };
    let e = read_signal(&p, &section).unwrap_err().to_string();
    assert!(
        e.contains("run from 0 s to 0.002 s: choose --from-s/--to-s"),
        "{e}"
    );
}
