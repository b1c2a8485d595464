//! Probe-grid assembly: tip compensation, bad inputs named by row (issue 7).

use runout_core::grind::*;
use std::f64::consts::TAU;

fn pt(row: usize, layer: i64, u: f64, angle_deg: f64, r: f64) -> ProbePoint {
    ProbePoint {
        row,
        layer: Some(layer),
        u_mm: Some(u),
        angle: angle_deg.to_radians(),
        touch: Touch::Radius(r),
    }
}

/// 3 layers × 4 angles of a 3 mm bar, rows numbered from 1.
fn good() -> Vec<ProbePoint> {
    let mut v = Vec::new();
    for (i, u) in [5.0, 10.0, 15.0].iter().enumerate() {
        for a in [0.0, 90.0, 180.0, 270.0] {
            v.push(pt(
                v.len() + 1,
                i as i64,
                *u,
                a,
                3.0 + 0.005 * a.to_radians().cos(),
            ));
        }
    }
    v
}

fn cyl() -> Generatrix {
    Generatrix::cylinder(3.0).unwrap()
}

fn err(points: &[ProbePoint], opts: &ProbeOptions) -> String {
    ProbeGrid::assemble(points, cyl(), opts)
        .unwrap_err()
        .to_string()
}

#[test]
fn good_grid_assembles() {
    let g = ProbeGrid::assemble(&good(), cyl(), &ProbeOptions::default()).unwrap();
    assert_eq!(g.layer_count(), 3);
    assert_eq!(g.layers[1].alpha.len(), 4);
    assert_eq!(g.u_range(), (5.0, 15.0));
    assert!(g.notes.is_empty());
}

#[test]
fn fewer_than_three_angles_names_the_rows() {
    let v: Vec<_> = good()
        .into_iter()
        .filter(|p| !(p.layer == Some(1) && p.angle > 2.0))
        .collect();
    // layer 1 keeps rows 5 and 6 (0° and 90°); missing points are skipped to reach this check
    let opts = ProbeOptions {
        missing: MissingPolicy::Skip,
        ..Default::default()
    };
    let e = err(&v, &opts);
    assert!(
        e.contains("layer 1") && e.contains("rows 5..6") && e.contains("2 distinct"),
        "{e}"
    );
}

#[test]
fn layers_not_increasing_names_the_row() {
    let mut v = good();
    for p in v.iter_mut().filter(|p| p.layer == Some(2)) {
        p.u_mm = Some(8.0);
    }
    let e = err(&v, &ProbeOptions::default());
    assert!(
        e.contains("row 9") && e.contains("u = 8 mm") && e.contains("10 mm"),
        "{e}"
    );
}

#[test]
fn layer_reappearing_is_refused() {
    let mut v = good();
    v[11].layer = Some(0);
    v[11].u_mm = Some(5.0);
    let e = err(&v, &ProbeOptions::default());
    assert!(e.contains("row 12") && e.contains("contiguous"), "{e}");
}

#[test]
fn nan_names_row_and_field() {
    let mut v = good();
    v[6].touch = Touch::Radius(f64::NAN);
    let e = err(&v, &ProbeOptions::default());
    assert!(e.contains("row 7") && e.contains("radius_mm"), "{e}");
    let mut v = good();
    v[3].angle = f64::NAN;
    assert!(err(&v, &ProbeOptions::default()).contains("row 4: `angle_deg`"));
    let mut v = good();
    v[0].touch = Touch::Point([3.0, f64::INFINITY, 5.0]);
    assert!(err(&v, &ProbeOptions::default()).contains("row 1: `y_mm`"));
}

#[test]
fn probe_miss_names_the_row() {
    let mut v = good();
    v[4].touch = Touch::Radius(2.5); // 0.5 mm inside: the probe fell past the bar
    let e = err(&v, &ProbeOptions::default());
    assert!(
        e.contains("row 5") && e.contains("probe miss") && e.contains("500.0 µm"),
        "{e}"
    );
}

#[test]
fn duplicates_refused_or_averaged() {
    let mut v = good();
    let mut d = v[2];
    d.row = 13;
    d.touch = Touch::Radius(3.001);
    v.insert(3, d);
    let e = err(&v, &ProbeOptions::default());
    assert!(
        e.contains("row 13") && e.contains("row 3") && e.contains("duplicate"),
        "{e}"
    );
    let opts = ProbeOptions {
        duplicates: DuplicatePolicy::Average,
        ..Default::default()
    };
    let g = ProbeGrid::assemble(&v, cyl(), &opts).unwrap();
    // row 3 is 180°: r = 2.995; averaged with 3.001 → 2.998
    assert!((g.layers[0].radius[2] - 2.998).abs() < 1e-12);
    assert_eq!(g.notes.len(), 1);
    assert!(g.notes[0].contains("row 13"));
}

#[test]
fn missing_point_refused_or_skipped() {
    let v: Vec<_> = good().into_iter().filter(|p| p.row != 10).collect();
    let e = err(&v, &ProbeOptions::default());
    assert!(
        e.contains("layer 2") && e.contains("90°") && e.contains("missing"),
        "{e}"
    );
    let opts = ProbeOptions {
        missing: MissingPolicy::Skip,
        ..Default::default()
    };
    let g = ProbeGrid::assemble(&v, cyl(), &opts).unwrap();
    assert_eq!(g.layers[2].alpha.len(), 3);
    assert!(g.notes[0].contains("layer 2"));
    // the first harmonic still works on the irregular layer: r = 3 + 0.005 cos α
    let map = DeviationMap::new(&g);
    assert!((map.layers[2].c - 0.005).abs() < 1e-12 && map.layers[2].s.abs() < 1e-12);
}

#[test]
fn single_layer_is_refused() {
    let v: Vec<_> = good().into_iter().filter(|p| p.layer == Some(0)).collect();
    assert!(err(&v, &ProbeOptions::default()).contains("1 layer(s)"));
}

/// Probe-tip compensation Q = C − r_tip·N (methods.md §5.1): on a cylinder the radius shrinks
/// by r_tip; on a cone the normal tilts and the radial shrink is r_tip/√(1 + R′²).
#[test]
fn tip_radius_compensation() {
    let opts = ProbeOptions {
        tip_radius_mm: 1.0,
        ..Default::default()
    };
    let v: Vec<_> = good()
        .into_iter()
        .map(|mut p| {
            if let Touch::Radius(r) = p.touch {
                p.touch = Touch::Radius(r + 1.0);
            }
            p
        })
        .collect();
    let g = ProbeGrid::assemble(&v, cyl(), &opts).unwrap();
    assert!((g.layers[0].radius[0] - 3.005).abs() < 1e-12);
    // cone R(u) = 2 + 0.1 u: slope 0.1
    let cone = Generatrix::table(vec![0.0, 20.0], vec![2.0, 4.0]).unwrap();
    let k = 1.0 / (1.0f64 + 0.01).sqrt();
    let pts: Vec<ProbePoint> = (0..2)
        .flat_map(|i| {
            (0..4).map(move |j| {
                let u = 5.0 + 5.0 * i as f64;
                let a = TAU * j as f64 / 4.0;
                let r = 2.0 + 0.1 * u;
                // tip centre = surface point + r_tip N
                let c = [(r + k) * a.cos(), (r + k) * a.sin(), u - 0.1 * k];
                ProbePoint {
                    row: 1 + 4 * i + j,
                    layer: Some(i as i64),
                    u_mm: Some(u),
                    angle: a,
                    touch: Touch::Point(c),
                }
            })
        })
        .collect();
    let g = ProbeGrid::assemble(&pts, cone, &opts).unwrap();
    for (l, r) in g.layers.iter().zip([2.5, 3.0]) {
        for x in &l.radius {
            assert!((x - r).abs() < 1e-12, "{x} vs {r}");
        }
    }
}
