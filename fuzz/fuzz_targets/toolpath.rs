//! APT CL and CSV toolpaths, joint tables, and the CL path built from them.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_core::chip::{ClPath, JointPath};
use runout_io::toolpath::{joint_points, parse_apt, parse_cl_csv, parse_joint_csv};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for parsed in [parse_apt("f.apt", text), parse_cl_csv("f.csv", text)] {
        if let Ok(mut tp) = parsed {
            if let Ok(cl) = tp.cl_points("f", Some(600.0)) {
                if let Ok(p) = ClPath::new(&cl) {
                    assert!(p.duration().is_finite());
                }
            }
        }
    }
    if let Ok(blocks) = parse_joint_csv("j.csv", text) {
        if let Ok(pts) = joint_points("j.csv", &blocks, Some(600.0)) {
            let _ = JointPath::new(&pts, 150.0);
        }
    }
});
