//! APT CL and CSV toolpath readers.

use runout_io::toolpath::{parse_apt, parse_cl_csv, read_toolpath, ToolpathError};

/// A realistic 5-axis flank-milling CL file as written by a CAM post (NX/CATIA style).
const FLANK_APT: &str = "\
$$ -> CLSF generated for flank milling of an impeller blade
$$ -> MFGNO,  blade_07
PARTNO/BLADE_07_FLANK
UNITS/MM
MACHIN/MILL, 5
CUTTER/10.000000, 0.000000, 0.000000, 0.000000, 0.000000, $
   0.000000, 50.000000
LOADTL/1,ADJUST,1
SPINDL/RPM,6000.000000,CLW
MULTAX/ON
RAPID
GOTO/-20.0000,0.0000,50.0000,0.000000,0.000000,1.000000
RAPID
GOTO/-20.0000,0.0000,5.0000,0.000000,0.000000,1.000000
FEDRAT/MMPM,2400.0000
GOTO/-10.0000,0.0000,5.0000,0.000000,0.000000,1.000000
GOTO/0.0000,0.0000,5.0000,0.000000,0.087156,0.996195  $$ start of the swing
GOTO/10.0000,0.0000,5.0000,0.000000,0.173648,$
     0.984808
$$ continuation above; a comment line between statements
GOTO/20.0000,0.5000,5.0000,0.000000,0.258819,0.965926
COOLNT/OFF
RAPID
GOTO/20.0000,0.5000,50.0000,0.000000,0.000000,1.000000
END-OF-PATH
FINI
";

#[test]
fn reads_realistic_flank_apt() {
    let mut p = parse_apt("blade.cls", FLANK_APT).unwrap();
    assert_eq!(p.points.len(), 7);
    assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    let cont = &p.points[4];
    assert_eq!(cont.line, 18);
    assert!((cont.axis[1] - 0.173648).abs() < 1e-6 && (cont.axis[2] - 0.984808).abs() < 1e-6);
    assert!(p.points[0].rapid && p.points[1].rapid && !p.points[2].rapid);
    assert_eq!(p.points[2].feed_mm_min, Some(2400.0));
    // the cutting section: from the rapid approach point to the last feed point
    let cl = p.cl_points("blade.cls", None).unwrap();
    assert_eq!(cl.len(), 5);
    assert!((cl[0].feed - 40.0).abs() < 1e-12); // 2400 mm/min = 40 mm/s
    assert!((cl[4].p.x - 20.0).abs() < 1e-12);
    let path = runout_core::chip::ClPath::new(&cl).unwrap();
    assert!((path.time_of_point(1) - 0.25).abs() < 1e-12); // 10 mm at 40 mm/s
}

#[test]
fn three_axis_apt_without_multax_and_inches() {
    let apt = "UNITS/INCHES\nFEDRAT/ 20.0, IPM\nGOTO / 0, 0, 0\nGOTO/1.0,0,0\n";
    let p = parse_apt("a.apt", apt).unwrap();
    assert_eq!(p.points[1].p[0], 25.4);
    assert_eq!(p.points[1].axis, [0.0, 0.0, 1.0]);
    assert!((p.points[1].feed_mm_min.unwrap() - 508.0).abs() < 1e-9);
}

fn parse_err(e: ToolpathError) -> (usize, String) {
    match e {
        ToolpathError::Parse { line, message, .. } => (line, message),
        other => panic!("expected a parse error, got {other}"),
    }
}

#[test]
fn malformed_apt_lines_name_the_line() {
    let (line, msg) = parse_err(
        parse_apt("x.apt", "MULTAX\nGOTO/0,0,0,0,0,1\nGOTO/1,0,abc,0,0,1\n").unwrap_err(),
    );
    assert_eq!(line, 3);
    assert!(msg.contains("abc"), "{msg}");
    let (line, msg) =
        parse_err(parse_apt("x.apt", "MULTAX\nGOTO/0,0,0,0,0,1\n$$ c\nGOTO/1,0,0\n").unwrap_err());
    assert_eq!(line, 4);
    assert!(msg.contains("6 values"), "{msg}");
    let (line, _) = parse_err(parse_apt("x.apt", "GOTO/1,2,3,4\n").unwrap_err());
    assert_eq!(line, 1);
    let (line, msg) = parse_err(parse_apt("x.apt", "GOTO/0,0,0\nFEDRAT/MMPR,0.1\n").unwrap_err());
    assert_eq!(line, 2);
    assert!(msg.contains("per revolution"));
    let (line, _) =
        parse_err(parse_apt("x.apt", "GOTO/0,0,0\nCIRCLE/0,0,0,0,0,1,5\n").unwrap_err());
    assert_eq!(line, 2);
    // the error message names file and line
    let e = parse_apt("part.apt", "\n\nGOTO/1,,2\n").unwrap_err();
    assert!(e.to_string().starts_with("part.apt:3:"), "{e}");
}

#[test]
fn zero_axis_is_an_error_non_unit_is_normalised_with_warning() {
    let (line, msg) =
        parse_err(parse_apt("z.apt", "MULTAX\nGOTO/0,0,0,0,0,1\nGOTO/1,0,0,0,0,0\n").unwrap_err());
    assert_eq!(line, 3);
    assert!(msg.contains("zero length"));
    let p = parse_apt("n.apt", "MULTAX\nGOTO/0,0,0,0,3,4\n").unwrap();
    assert_eq!(p.warnings.len(), 1);
    assert!(p.warnings[0].contains("n.apt:2") && p.warnings[0].contains("normalised"));
    assert!((p.points[0].axis[1] - 0.6).abs() < 1e-15 && (p.points[0].axis[2] - 0.8).abs() < 1e-15);
    let (line, _) =
        parse_err(parse_cl_csv("z.csv", "0,0,0,0,0,1,100\n1,0,0,0,0,0,100\n").unwrap_err());
    assert_eq!(line, 2);
}

#[test]
fn csv_toolpath() {
    let csv = "# swing about y\nx_mm,y_mm,z_mm,i,j,k,feed_mm_min\n0,0,0,0,0,1,1200\n\n5,0,0,0.0871557,0,0.9961947,1200\n10,0,0,0.17,0,0.98\n";
    let mut p = parse_cl_csv("p.csv", csv).unwrap();
    assert_eq!(p.points.len(), 3);
    assert_eq!(p.points[2].feed_mm_min, Some(1200.0)); // modal
    assert_eq!(p.points[2].line, 6);
    assert_eq!(p.warnings.len(), 1); // (0.17, 0, 0.98) is not unit
    let cl = p.cl_points("p.csv", None).unwrap();
    assert_eq!(cl.len(), 3);
    let (line, msg) = parse_err(parse_cl_csv("p.csv", "0,0,0,0,0,1\n1,2,3\n").unwrap_err());
    assert_eq!(line, 2);
    assert!(msg.contains("6 or 7 fields"));
    let (line, _) = parse_err(parse_cl_csv("p.csv", "x,y,z,i,j,k\n").unwrap_err());
    assert_eq!(line, 1);
    let (line, _) = parse_err(parse_cl_csv("p.csv", "0,0,0,0,0,1,-5\n").unwrap_err());
    assert_eq!(line, 1);
}

#[test]
fn missing_feed_is_reported() {
    let mut p = parse_cl_csv("p.csv", "0,0,0,0,0,1\n1,0,0,0,0,1\n").unwrap();
    let e = p.cl_points("p.csv", None).unwrap_err();
    assert!(e.to_string().contains("no feed"), "{e}");
    let cl = p.cl_points("p.csv", Some(600.0)).unwrap();
    assert!((cl[0].feed - 10.0).abs() < 1e-12);
}

#[test]
fn read_toolpath_by_extension() {
    let dir = tempfile::tempdir().unwrap();
    let apt = dir.path().join("path.cls");
    std::fs::write(&apt, FLANK_APT).unwrap();
    assert_eq!(read_toolpath(&apt).unwrap().points.len(), 7);
    let csv = dir.path().join("path.csv");
    std::fs::write(&csv, "0,0,0,0,0,1,100\n1,0,0,0,0,1,100\n").unwrap();
    assert_eq!(read_toolpath(&csv).unwrap().points.len(), 2);
    let e = read_toolpath(&dir.path().join("missing.apt")).unwrap_err();
    assert!(e.to_string().contains("missing.apt"));
}

#[test]
fn joint_csv_for_machines_without_rtcp() {
    use runout_io::toolpath::{joint_points, parse_joint_csv};
    let text =
        "# head-head\nx_mm,y_mm,z_mm,a_deg,c_deg,feed_mm_min\n0,0,150,0,0,600\n10,0,150,5,90\n";
    let blocks = parse_joint_csv("j.csv", text).unwrap();
    assert_eq!(blocks.len(), 2);
    assert_eq!(blocks[1].line, 4);
    let pts = joint_points("j.csv", &blocks, None).unwrap();
    assert!((pts[1].c - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert!((pts[0].feed - 10.0).abs() < 1e-12); // 600 mm/min
    let path = runout_core::chip::JointPath::new(&pts, 150.0).unwrap();
    assert!(path.duration() > 0.0);
    let (line, msg) =
        parse_err(parse_joint_csv("j.csv", "0,0,150,0,0,600\n1,0,150,x,0\n").unwrap_err());
    assert_eq!(line, 2);
    assert!(msg.contains("`x`"), "{msg}");
    let (line, _) = parse_err(parse_joint_csv("j.csv", "0,0,150,0\n").unwrap_err());
    assert_eq!(line, 1);
    let blocks = parse_joint_csv("j.csv", "0,0,150,0,0\n1,0,150,0,0\n").unwrap();
    assert!(joint_points("j.csv", &blocks, None)
        .unwrap_err()
        .to_string()
        .contains("no feed"));
}

/// Issue 20 row 9: a record that is not an APT word (`GOT0`, a typo) is an error naming the line;
/// an unknown word is a warning naming the line; coordinates and feeds out of range are errors.
#[test]
fn unknown_records_and_out_of_range_numbers_are_not_dropped_silently() {
    let base = "MULTAX/ON\nFEDRAT/MMPM,1200\nGOTO/0,0,5,0,0,1\n";
    let e = parse_apt("t.apt", &format!("{base}GOT0/4,0,5,0,0,1\n")).unwrap_err();
    assert!(
        matches!(&e, ToolpathError::Parse { line: 4, message, .. } if message.contains("GOT0")),
        "{e}"
    );
    let p = parse_apt("t.apt", &format!("{base}FOOBAR/1\nGOTO/4,0,5,0,0,1\n")).unwrap();
    assert_eq!(p.points.len(), 2);
    assert!(
        p.warnings
            .iter()
            .any(|w| w.contains("t.apt:4") && w.contains("FOOBAR")),
        "{:?}",
        p.warnings
    );
    let e = parse_apt("t.apt", &format!("{base}GOTO/1e300,0,5,0,0,1\n")).unwrap_err();
    assert!(e.to_string().contains("t.apt:4") && e.to_string().contains("100000"));
    let e = parse_apt("t.apt", "FEDRAT/MMPM,1e-300\nGOTO/0,0,5\n").unwrap_err();
    assert!(e.to_string().contains("t.apt:1") && e.to_string().contains("[0.001, 1000000] mm/min"));
    let e = parse_cl_csv("p.csv", "0,0,0,0,0,1,600\n1e9,0,0,0,0,1\n").unwrap_err();
    assert!(e.to_string().contains("p.csv:2"), "{e}");
}
