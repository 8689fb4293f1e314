//! A liquid tank's share of the Lagrangian (Beghin §66–67), in world axes on the carrier's
//! kinematics.
//!
//! - Each compartment's oil is a column of height c + hᵢ over its floor area Sᵢ: a point mass
//!   ρSᵢ(c + hᵢ) at its centroid, half-way up, moving with the carrier (weight, transport and
//!   Coriolis terms from the chain's kinematics, as the pots' columns). The weight of the
//!   levels gives Beghin's ϖa Sᵢ hᵢ moments and the head differences that drive the flow.
//! - The free surfaces stay normal to the apparent gravity g_c (carrier axes) while the
//!   columns tilt with the carrier: each surface's wedge lowers the potential by
//!   ½ρ(I_x g_{c,y}² + I_y g_{c,x}²)/|g_c| (to second order in the tilt), which reduces the
//!   righting moment Πf by ϖE about one axis and ϖF about the other (Beghin's (49)–(50)).
//! - The relative flow's own kinetic energy ½ḣᵀℳḣ (plug flow; `design::tank`), unless the
//!   fidelity drops it. Its coupling to the carrier's motion is left out, as Beghin leaves it.
//!
//! The flow's loss is a set of dampers the design reader adds.

use super::pots::{Terms, carried_mass};
use super::{BodyKin, EvalInput};
use crate::design::Tank;
use crate::dual::{Jet, Real, V3};

/// Adds one tank, carried by a body with kinematics `k`, to the Lagrangian's terms.
#[allow(clippy::too_many_arguments)]
pub(super) fn add<T: Real, const N: usize>(
    tank: &Tank,
    k: &BodyKin<Jet<T, N>, N>,
    q: &[Jet<T, N>; N],
    n: usize,
    inp: &EvalInput<T>,
    w0: &V3<Jet<T, N>>,
    mut out: Terms<T, N>,
) {
    let rho = tank.density_kg_per_m3;
    let c = tank.rest_depth_m;
    for (i, comp) in tank.compartments.iter().enumerate() {
        let mut h = Jet::<T, N>::zero();
        for (&a, &l) in tank.level_coefficients(i).iter().zip(&tank.levels) {
            if a != 0.0 {
                h += q[l] * a;
            }
        }
        let height = h + c;
        let r_body = V3([
            Jet::cst(comp.centroid_m[0]),
            Jet::cst(comp.centroid_m[1]),
            height * 0.5 + tank.floor_height_m,
        ]);
        carried_mass(
            k,
            &r_body,
            height * (rho * comp.area_m2),
            n,
            inp,
            w0,
            out.reborrow(),
        );
    }

    // Free surfaces: −½ρ Σ (I_x g_y² + I_y g_x²)/|g|, g in the carrier's axes.
    let (ix, iy) = tank.compartments.iter().fold((0.0, 0.0), |(x, y), c| {
        (x + c.free_surface_m4[0], y + c.free_surface_m4[1])
    });
    if ix != 0.0 || iy != 0.0 {
        let gc = k.r.tmul_v(&V3(inp.gravity.map(Jet::constant)));
        let norm = gc.dot(&gc).sqrt();
        let wedge = (gc.0[1] * gc.0[1] * ix + gc.0[0] * gc.0[0] * iy) / norm;
        *out.v -= wedge * (0.5 * rho);
    }

    // The flow's own kinetic energy, constant in the level rates.
    let dropped = |i: usize| inp.drop_quadratic.get(i).copied().unwrap_or(false);
    let m = tank.levels.len();
    for (r, &ir) in tank.levels.iter().enumerate() {
        if dropped(ir) {
            continue;
        }
        let mut p = Jet::<T, N>::zero();
        for (s, &is) in tank.levels.iter().enumerate() {
            let e = tank.flow_inertia[r * m + s];
            if dropped(is) || e == 0.0 {
                continue;
            }
            p += Jet::constant(inp.u[is] * e);
            out.m[ir * n + is] += T::cst(e);
        }
        out.p2[ir] += p;
        *out.t2 += p * Jet::constant(inp.u[ir]) * 0.5;
    }
}
