//! NC programs: lexer, modal program, and the rewrite with offsets on every motion block.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::gcode::{lex, NcProgram, RewriteOptions};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = lex(text);
    if let Ok(p) = NcProgram::parse(text) {
        let offsets = vec![Some([0.001, -0.002, 0.0]); p.motion_blocks().len()];
        if let Ok(out) = p.rewrite(&offsets, &RewriteOptions::default()) {
            assert!(!out.contains("inf") || text.contains("inf"));
        }
        let zero = vec![None; p.motion_blocks().len()];
        assert_eq!(p.rewrite(&zero, &RewriteOptions::default()).unwrap(), text);
    }
});
