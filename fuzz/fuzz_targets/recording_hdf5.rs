//! Binary recordings, hdf5 (issue 16): open, list, read every chunk — never a panic. Also the
//! 2-D dataset columns (`D[:,k]`, named columns) and the displacement signal read through the
//! generic reader (`read_signal_with`, channel mapping and time variable).
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::displacement::{read_signal_with, SignalOptions, SignalSection, TableInput};
use runout_io::formats::{open_bytes, Kind};
use runout_io::recording::{recording_from_bytes, RecordingChunk, ReadOptions};

fuzz_target!(|data: &[u8]| {
    // the parser directly (whatever the magic bytes say) …
    let _ = open_bytes(Kind::Hdf5 { offset: 0 }, data, "fuzz");
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
    // columns of a 2-D dataset, by position and by name, selected as a group
    let o = ReadOptions::new().channels(&["data[:,0]", "M(:,2)"]).sample_rate_hz(1000.0);
    let _ = recording_from_bytes("fuzz", data, None, &o).map(|mut r| r.read_chunk(&mut RecordingChunk::default(), 4096));
    let _ = recording_from_bytes("fuzz", data, Some("data"), &ReadOptions::new().time_column("fs"));
    // the displacement signal layer
    let section = SignalSection { max_samples: 1 << 20, ..Default::default() };
    for opts in [
        SignalOptions { channels: Some("a = data[:,0] [um], pulse = data/Fy".into()), time_var: None, sample_rate_hz: Some(1000.0) },
        SignalOptions { channels: None, time_var: Some("t".into()), sample_rate_hz: None },
    ] {
        let input = TableInput::Reader { name: "fuzz", reader: Box::new(data), len: Some(data.len() as u64) };
        let _ = read_signal_with(input, &section, &opts);
    }
});
