//! Issue 16 (session 6): MATLAB struct arrays and cell arrays, 2-D HDF5 / MAT matrices, the
//! displacement signal through the generic reader, and mutated bytes on these paths. The values
//! are checked against the independent writers in `formats.rs` (expected.json); here: what
//! `inspect` lists, the errors, and the signal layer.

use proptest::prelude::*;
use runout_io::displacement::{read_signal_with, SignalOptions, SignalSection, TableInput};
use runout_io::formats::{column_spelling, inspect};
use runout_io::recording::{open_recording, ReadOptions, RecordingChunk};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

#[test]
fn inspect_lists_struct_array_fields_cells_and_matrix_columns() {
    let c = inspect(&fixture("mat5_cells.mat"), &ReadOptions::new()).unwrap();
    let names: Vec<&str> = c.entries.iter().map(|e| e.name.as_str()).collect();
    for want in [
        "s(1).Fx", "s(1).Fy", "s(2).Fx", "s(2).Fy", "c{1}", "c{2}", "c{3}", "fs",
    ] {
        assert!(names.contains(&want), "{want} not in {names:?}");
    }
    let s2 = c.entries.iter().find(|e| e.name == "s(2).Fy").unwrap();
    assert_eq!(
        (s2.group.as_deref(), s2.short.as_str(), s2.len),
        (Some("s(2)"), "Fy", 200)
    );
    let text = c.entries.iter().find(|e| e.name == "c{3}").unwrap();
    assert!(
        !text.readable && text.note.as_deref().unwrap().contains("char"),
        "{text:?}"
    );

    let c = inspect(&fixture("matrix.h5"), &ReadOptions::new()).unwrap();
    let col = c.entries.iter().find(|e| e.name == "/data[:,2]").unwrap();
    assert_eq!((col.len, col.unit.as_deref()), (200, Some("N")));
    assert!(col
        .note
        .as_deref()
        .unwrap()
        .contains("column 2 of the 200×3 dataset `/data`"));
    let named = c.entries.iter().find(|e| e.name == "/data/Fz").unwrap();
    assert_eq!(
        (named.group.as_deref(), named.short.as_str()),
        (Some("/data"), "Fz")
    );
    let t = c.entries.iter().find(|e| e.name == "/dataT[:,1]").unwrap();
    assert!(
        t.note.as_deref().unwrap().contains("3×200")
            && t.note.as_deref().unwrap().contains("by row")
    );

    let c = inspect(&fixture("mat73_matrix.mat"), &ReadOptions::new()).unwrap();
    let names: Vec<&str> = c.entries.iter().map(|e| e.name.as_str()).collect();
    for want in ["s.Fx", "s.Fy", "M(:,1)", "M(:,2)", "fs"] {
        assert!(names.contains(&want), "{want} not in {names:?}");
    }
}

#[test]
fn a_cell_that_is_not_numeric_is_refused_by_name() {
    let e = open_recording(
        fixture("mat5_cells.mat"),
        &ReadOptions::new().channels(&["c{3}"]),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("mat5_cells.mat")
            && e.contains("`c{3}` is not a numeric vector")
            && e.contains("char array"),
        "{e}"
    );
    // a column past the end: missing, with the listing
    let e = open_recording(
        fixture("matrix.h5"),
        &ReadOptions::new().channels(&["data[:,3]"]),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("data[:,3]") && e.contains("/data[:,2]"), "{e}");
}

#[test]
fn column_spellings() {
    assert_eq!(column_spelling("D[:,0]").as_deref(), Some("D(:,1)"));
    assert_eq!(column_spelling("rec.M(:,3)").as_deref(), Some("rec.M[:,2]"));
    assert_eq!(column_spelling("M(:,0)"), None);
    assert_eq!(column_spelling("Fx"), None);
}

/// A displacement signal written as a 2-D dataset: the same table through a path and through
/// bytes in memory, selected by the mapping.
#[test]
fn displacement_signal_from_a_matrix_by_mapping() {
    let opts = SignalOptions {
        channels: Some("a = data/Fx [um], b = data[:,1] [mm]".into()),
        time_var: None,
        sample_rate_hz: None, // the root attribute fs = 1000 Hz
    };
    let p = fixture("matrix.h5");
    let t = read_signal_with(&p, &SignalSection::default(), &opts).unwrap();
    assert_eq!(t.sample_rate_hz, 1000.0);
    assert_eq!(t.channels[0].0, "a");
    assert_eq!(t.channels[1].1.len(), 200);
    let mut r = open_recording(
        &p,
        &ReadOptions::new().channels(&["data[:,0]", "data[:,1]"]),
    )
    .unwrap();
    let mut c = RecordingChunk::default();
    r.read_chunk(&mut c, 1000).unwrap();
    let want_a: Vec<f64> = c.values[0].iter().map(|v| v * 1e-3).collect();
    assert_eq!(t.channels[0].1, want_a); // µm → mm
    assert_eq!(t.channels[1].1, c.values[1]); // mm
    let bytes = std::fs::read(&p).unwrap();
    let m = read_signal_with(
        TableInput::Reader {
            name: "mem.h5",
            reader: Box::new(&bytes[..]),
            len: Some(bytes.len() as u64),
        },
        &SignalSection::default(),
        &opts,
    )
    .unwrap();
    assert_eq!(m, t);
    // the section applies on the file's time base
    let sec = SignalSection {
        from_s: Some(0.05),
        to_s: Some(0.0995),
        ..Default::default()
    };
    let s = read_signal_with(&p, &sec, &opts).unwrap();
    assert_eq!((s.channels[0].1.len(), s.start_s), (50, 0.05));
    // no unit stated anywhere: the mapping asks for one
    let e = read_signal_with(
        &fixture("mat5_cells.mat"),
        &SignalSection::default(),
        &SignalOptions {
            channels: Some("a = c{1}".into()),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("c{1}") && e.contains("[um]"), "{e}");
}

const SIGNAL_FIXTURES: [&str; 4] = [
    "matrix.h5",
    "mat5_cells.mat",
    "mat73_matrix.mat",
    "signal_ms.h5",
];

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64),
        ..ProptestConfig::default()
    })]

    /// Mutated and truncated bytes through the displacement signal layer (channel mapping onto
    /// matrix columns, cells, struct fields): `Ok` or an error naming the input, never a panic.
    #[test]
    fn mutated_structured_files_through_the_signal_layer(
        which in 0..SIGNAL_FIXTURES.len(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        cut in any::<prop::sample::Index>(),
        truncate in any::<bool>(),
    ) {
        let mut b = std::fs::read(fixture(SIGNAL_FIXTURES[which])).unwrap();
        for (at, v) in &edits {
            let i = at.index(b.len());
            b[i] = *v;
        }
        if truncate {
            let n = cut.index(b.len());
            b.truncate(n.max(1));
        }
        for map in [Some("a = data/Fx [um], pulse = dataT[:,0]"), Some("a = c{1} [mm], b = s(2).Fy [um]"), Some("a = M(:,2) [um], b = s.Fx [um]"), None] {
            let opts = SignalOptions { channels: map.map(str::to_string), time_var: None, sample_rate_hz: map.map(|_| 1000.0) };
            let r = read_signal_with(
                TableInput::Reader { name: "mutated-input", reader: Box::new(&b[..]), len: Some(b.len() as u64) },
                &SignalSection::default(),
                &opts,
            );
            if let Err(e) = r {
                let e = e.to_string();
                prop_assert!(e.contains("mutated-input") || e.contains("--channels"), "{}", e);
            }
        }
    }
}

/// A binary signal whose `time_<unit>` channel is not in seconds: converted, and the grid and a
/// given rate checked on the converted times.
#[test]
fn displacement_signal_with_times_in_ms_from_hdf5() {
    let p = fixture("signal_ms.h5");
    let t = read_signal_with(&p, &SignalSection::default(), &SignalOptions::default()).unwrap();
    assert!(
        (t.sample_rate_hz - 20_000.0).abs() < 1e-6,
        "{}",
        t.sample_rate_hz
    );
    assert_eq!(t.channels[0].0, "a");
    assert_eq!(t.channels[0].1.len(), 400);
    assert!((t.channels[0].1[0] - 0.008).abs() < 1e-15); // 8 µm in mm
    let agree = SignalOptions {
        sample_rate_hz: Some(20_000.0),
        ..Default::default()
    };
    assert_eq!(
        read_signal_with(&p, &SignalSection::default(), &agree).unwrap(),
        t
    );
    let disagree = SignalOptions {
        sample_rate_hz: Some(21_000.0),
        ..Default::default()
    };
    let e = read_signal_with(&p, &SignalSection::default(), &disagree)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("signal_ms.h5") && e.contains("sample ") && e.contains("--sample-rate-hz"),
        "{e}"
    );
}
