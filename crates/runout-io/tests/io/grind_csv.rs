//! Probe / edge CSV readers and the compensated-path writer; errors name the file line.

use runout_core::grind::*;
use runout_io::grind::{read_edge_csv, read_probe_csv, write_path_csv};

fn grid_text(rows: &[(i64, f64, f64, f64)]) -> String {
    let mut s = String::from("# probe export\nlayer,u_mm,angle_deg,radius_mm\n");
    for (l, u, a, r) in rows {
        s += &format!("{l},{u},{a},{r}\n");
    }
    s
}

fn rows() -> Vec<(i64, f64, f64, f64)> {
    let mut v = Vec::new();
    for (i, u) in [4.0, 12.0, 20.0].iter().enumerate() {
        for a in [0.0f64, 90.0, 180.0, 270.0] {
            let r = 3.0 + 0.006 * a.to_radians().cos() + 0.0001 * u;
            v.push((i as i64, *u, a, r));
        }
    }
    v
}

fn assemble(text: &str) -> Result<ProbeGrid, String> {
    let pts = read_probe_csv(text, "probe.csv").map_err(|e| e.to_string())?;
    ProbeGrid::assemble(
        &pts,
        Generatrix::cylinder(3.0).unwrap(),
        &ProbeOptions::default(),
    )
    .map_err(|e| e.to_string())
}

#[test]
fn reads_a_probe_grid_with_line_numbers() {
    let g = assemble(&grid_text(&rows())).unwrap();
    assert_eq!(g.layer_count(), 3);
    // data start on line 3 (comment line 1, header line 2)
    assert_eq!(g.layers[0].rows, vec![3, 4, 5, 6]);
    let m = DeviationMap::new(&g);
    assert!((m.axis.offset[0].value - 0.006).abs() < 1e-12);
}

#[test]
fn xyz_points_with_u_from_z() {
    let mut s = String::from("layer,angle_deg,x_mm,y_mm,z_mm\n");
    for (i, z) in [5.0, 10.0].iter().enumerate() {
        for a in [0.0f64, 120.0, 240.0] {
            let r = 3.0 + 0.002 * a.to_radians().sin();
            let (x, y) = (r * a.to_radians().cos(), r * a.to_radians().sin());
            s += &format!("{i},{a},{x},{y},{z}\n");
        }
    }
    let g = assemble(&s).unwrap();
    assert_eq!(g.u_range(), (5.0, 10.0));
    let m = DeviationMap::new(&g);
    assert!((m.layers[1].s - 0.002).abs() < 1e-12);
}

#[test]
fn errors_name_the_line() {
    let mut r = rows();
    let text = grid_text(&r).replace(",4,90,", ",4,9O,");
    let e = assemble(&text).unwrap_err();
    assert!(
        e.contains("probe.csv:4:3: `9O` in column `angle_deg` is not a number"),
        "{e}"
    );

    r[5].3 = f64::NAN; // line 8
    let e = assemble(&grid_text(&r)).unwrap_err();
    assert!(
        e.contains("probe.csv:8:4: ") && e.contains("radius_mm"),
        "{e}"
    );

    let mut r = rows();
    r[9].3 = 3.4; // probe miss on line 12
    let e = assemble(&grid_text(&r)).unwrap_err();
    assert!(e.contains("row 12") && e.contains("probe miss"), "{e}");

    let mut r = rows();
    for x in r.iter_mut().filter(|x| x.0 == 2) {
        x.1 = 8.0; // layer 2 below layer 1
    }
    let e = assemble(&grid_text(&r)).unwrap_err();
    assert!(
        e.contains("row 11") && e.contains("does not increase"),
        "{e}"
    );

    let r: Vec<_> = rows()
        .into_iter()
        .filter(|x| !(x.0 == 0 && x.2 >= 180.0))
        .collect();
    let text = grid_text(&r);
    let pts = read_probe_csv(&text, "probe.csv").unwrap();
    let opts = ProbeOptions {
        missing: MissingPolicy::Skip,
        ..Default::default()
    };
    let e = ProbeGrid::assemble(&pts, Generatrix::cylinder(3.0).unwrap(), &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("rows 3..4") && e.contains("at least 3"), "{e}");

    let e = read_probe_csv("layer,u,angle_deg,radius_mm\n0,1,2,3\n", "p.csv").unwrap_err();
    assert!(
        e.to_string().starts_with("p.csv:1: unknown column `u`"),
        "{e}"
    );
    let e = read_probe_csv("layer,u_mm,angle_deg\n0,1,2\n", "p.csv").unwrap_err();
    assert!(e.to_string().contains("radius_mm"));
    let e = read_probe_csv("layer,u_mm,angle_deg,radius_mm\n0,1,2\n", "p.csv").unwrap_err();
    assert!(
        e.to_string().starts_with("p.csv:2: 3 fields, expected 4"),
        "{e}"
    );
}

#[test]
fn edge_csv_and_path_writer() {
    let e = read_edge_csv(
        "x_mm,y_mm,z_mm,nx,ny,nz,wx_mm,wy_mm,wz_mm\n3,0,5,2,0,0,10,0,5\n0,3,6,0,1,0,0,10,6\n",
        "edge.csv",
    )
    .unwrap();
    assert_eq!(e.lines, vec![2, 3]);
    let edge = EdgeLine::from_points(&e.points, e.normals.as_deref()).unwrap();
    assert_eq!(edge.points[0].normal, [1.0, 0.0, 0.0]);
    let g = assemble(&grid_text(&rows())).unwrap();
    let map = DeviationMap::new(&g);
    let f = Interpolator::new(&map, Scheme::FirstHarmonic, RangePolicy::Clamp);
    let comp = compensate(&f, &map.axis, &edge, e.wheel.as_deref()).unwrap();
    // ε at α = 0 is the x offset 6 µm; the wheel at x = 10 moves to 10.006
    assert!((comp.points[0].compensated[0] - 10.006).abs() < 1e-9);
    let mut buf = Vec::new();
    write_path_csv(&mut buf, &edge, &comp).unwrap();
    let text = String::from_utf8(buf).unwrap();
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let h = rdr.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|x| x == n).unwrap();
    let recs: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
    assert_eq!(recs.len(), 2);
    let eps: f64 = recs[0][col("eps_um")].parse().unwrap();
    assert!((eps - 6.0).abs() < 1e-4);
    let wx: f64 = recs[0][col("wx_comp_mm")].parse().unwrap();
    assert!((wx - 10.006).abs() < 1e-6);

    let bad = read_edge_csv("x_mm,y_mm,z_mm,nx\n1,2,3,4\n", "edge.csv").unwrap_err();
    assert!(bad.to_string().contains("nx, ny, nz"));
}

/// Issue 21 item 7: every map has a colour bar labelled with its unit — the grind deviation heat
/// map (δ in µm, −max … +max) and the chip path × height map (h in µm).
#[test]
fn heat_maps_have_colour_bars_with_units() {
    let g = assemble(&grid_text(&rows())).unwrap();
    let map = DeviationMap::new(&g);
    let svg = runout_io::grind::plot::deviation_heatmap_svg(&map).unwrap();
    assert!(
        svg.contains("δ (µm)"),
        "no colour-bar label in the deviation map"
    );
    // the bar is 100 bands; the map itself is 12 cells (a few split at 0°/360°)
    let rects = svg.matches("<rect").count();
    assert!(rects >= 100 + 12, "{rects} rectangles: no colour bar");
    let d = std::env::temp_dir().join(format!("runout-map-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let f = d.join("chip_map.svg");
    let chip = runout_io::plot::chip::ChipMap {
        time_s: vec![0.0, 0.1, 0.2],
        height_mm: vec![0.5, 1.5],
        values: vec![vec![1.0, 2.0], vec![3.0, 4.0], vec![5.0, 6.0]],
    };
    runout_io::plot::chip::chip_map_plot(&f, &chip, "map").unwrap();
    let svg = std::fs::read_to_string(&f).unwrap();
    assert!(
        svg.contains("h (µm)"),
        "no colour-bar label in the chip map"
    );
    let _ = std::fs::remove_dir_all(&d);
}
