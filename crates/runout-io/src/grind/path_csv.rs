//! Compensated path writer.

use runout_core::grind::{Compensation, EdgeLine};
use std::io::Write;

/// Write one row per edge point: `index, flute, u_mm, alpha_deg, x_mm, y_mm, z_mm, nx, ny, nz,
/// eps_um, wx_mm, wy_mm, wz_mm, wx_comp_mm, wy_comp_mm, wz_comp_mm, before_um, remaining_um,
/// outside_probed_range` (methods.md §5.4: w′ = w + ε·N; `before_um` / `remaining_um` are the
/// predicted radial errors without / with compensation relative to the fitted bar axis).
pub fn write_path_csv<W: Write>(
    mut w: W,
    edge: &EdgeLine,
    comp: &Compensation,
) -> std::io::Result<()> {
    writeln!(
        w,
        "index,flute,u_mm,alpha_deg,x_mm,y_mm,z_mm,nx,ny,nz,eps_um,wx_mm,wy_mm,wz_mm,wx_comp_mm,wy_comp_mm,wz_comp_mm,before_um,remaining_um,outside_probed_range"
    )?;
    for (k, (p, c)) in edge.points.iter().zip(&comp.points).enumerate() {
        writeln!(
            w,
            "{k},{},{:.6},{:.6},{:.7},{:.7},{:.7},{:.9},{:.9},{:.9},{:.5},{:.7},{:.7},{:.7},{:.7},{:.7},{:.7},{:.5},{:.5},{}",
            p.flute,
            p.u,
            p.alpha.to_degrees(),
            p.position[0],
            p.position[1],
            p.position[2],
            p.normal[0],
            p.normal[1],
            p.normal[2],
            c.eps * 1e3,
            c.wheel[0],
            c.wheel[1],
            c.wheel[2],
            c.compensated[0],
            c.compensated[1],
            c.compensated[2],
            c.before * 1e3,
            c.remaining * 1e3,
            c.outside
        )?;
    }
    w.flush()
}
