//! Binary recordings, mat (issue 16): open, list, read every chunk — never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::formats::{open_bytes, Kind};
use runout_io::recording::{recording_from_bytes, RecordingChunk, ReadOptions};

fuzz_target!(|data: &[u8]| {
    // the parser directly (whatever the magic bytes say) …
    let _ = open_bytes(Kind::Mat5, data, "fuzz");
    // … and through detection, channel selection and chunked reads
    if let Ok(mut r) = recording_from_bytes("fuzz", data, None, &ReadOptions::new().sample_rate_hz(1000.0)) {
        let mut c = RecordingChunk::default();
        let mut n = 0u64;
        while let Ok(k) = r.read_chunk(&mut c, 4096) {
            if k == 0 || n > 1 << 24 {
                break;
            }
            n += k as u64;
        }
    }
});
