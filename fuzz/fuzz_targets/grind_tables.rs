//! Grind probe and edge tables, assembled into a probe grid and an edge line.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_core::grind::{DeviationMap, EdgeLine, Generatrix, ProbeGrid, ProbeOptions};
use runout_io::grind::{read_edge_csv, read_probe_csv};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(points) = read_probe_csv(text, "probe.csv") {
        let opts = ProbeOptions {
            tip_radius_mm: 1.0,
            ..ProbeOptions::default()
        };
        if let Ok(grid) = ProbeGrid::assemble(&points, Generatrix::cylinder(3.0).unwrap(), &opts) {
            let _ = DeviationMap::new(&grid);
        }
    }
    if let Ok(t) = read_edge_csv(text, "edge.csv") {
        let _ = EdgeLine::from_points(&t.points, t.normals.as_deref());
    }
});
