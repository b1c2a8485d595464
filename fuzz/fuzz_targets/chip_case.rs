//! A chip case set (TOML) with the toolpath it names: the input is the case text, then a line
//! `@@@`, then the toolpath text (written as `tp.apt` and `tp.csv` next to the case).
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::config::chip::{parse_case_specs, resolve_case};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let (case, path) = text.split_once("\n@@@\n").unwrap_or((text, ""));
    let Ok(specs) = parse_case_specs("case.toml", case) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tp.apt"), path).unwrap();
    std::fs::write(dir.path().join("tp.csv"), path).unwrap();
    std::fs::write(dir.path().join("joints.csv"), path).unwrap();
    for s in specs.into_iter().take(4) {
        if let Ok(c) = resolve_case("case.toml", dir.path(), s) {
            assert!(c.points.len() <= runout_core::limits::MAX_SAMPLES);
        }
    }
});
