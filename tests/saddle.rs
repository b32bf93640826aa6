//! A converged state that is a saddle of the incremental potential is left
//! (`src/solver/saddle.rs`): a slender elastic column, clamped at its foot and pressed by a
//! frictionless wall on its head (barrier contact), is compressed far past its buckling load.
//! Its mesh is symmetric about the column's axis, so the straight column is an equilibrium at
//! every load, and past the buckling load it is a saddle: Newton converges to it and the
//! gradient there has no component along the buckling mode. The run must leave it:
//! - at least one step is moved off a saddle ([`RunSummary::saddle_departures`]);
//! - the column ends buckled: its head moves sideways by more than its width;
//! - the wall force at the end lies between the Euler loads of the two idealisations of the
//!   head (Timoshenko & Gere, Theory of Elastic Stability, §2.1–2.3; plane strain, bending
//!   stiffness EI = E/(1 − ν²) w³/12 per unit thickness): a free head, P = π²EI/(4L²)
//!   (the wall touching one corner of the tilted head), and a head guided without rotation,
//!   P = π²EI/L² (the whole head on the wall); the elastica of a moderately bent column
//!   carries a few per cent more than the first, and the four elements across the column
//!   bend a little stiffly;
//! - and far below what the straight column would carry at the same shortening,
//!   E/(1 − ν²) ε w (less than a fifth of it).

use mpfem::case;
use mpfem::model::Model;
use mpfem::solver::Simulation;
use std::f64::consts::PI;
use std::path::Path;

const CASE: &str = r#"
title = "Slender column clamped at its foot, pressed by a frictionless wall past its buckling load"

[[materials]]
name = "rubber"
model = "elastic"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[[bodies]]
name = "column"
material = "rubber"
mesh_size = 1.0
shape = { type = "rectangle", origin = [8.0, 0.0], size = [4.0, 40.0] }

[[boundary]]
body = "column"
set = "bottom"
ux = 0.0
uy = 0.0

[[walls]]
side = "top"
position = 40.5
velocity = 1.0

[time]
end = 3.0
dt = 0.25
"#;

#[test]
fn a_column_past_its_buckling_load_leaves_the_straight_saddle() {
    let (e, nu, w, l) = (1000.0, 0.3, 4.0, 40.0);
    let c = case::parse(CASE, Path::new(".")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let mut forces = Vec::new();
    let mut head = 0.0f64;
    let summary = sim
        .run(&mut |s, r| {
            forces.push(r.compaction.as_ref().map_or(0.0, |c| c.force[3]));
            // the largest sideways move of a node of the head (y = 40 in the reference)
            let x = s.coords(&s.sol.u);
            head = s.model.x0.iter().zip(&x).filter(|(p, _)| p[1] > l - 1e-9).map(|(p, q)| (q[0] - p[0]).abs()).fold(0.0, f64::max);
        })
        .unwrap();
    assert!(summary.saddle_departures >= 1, "no step left a saddle ({} departures)", summary.saddle_departures);
    assert!(head > w, "the column did not buckle: its head moved {head} mm sideways");
    let f = *forces.last().unwrap();
    let ei = e / (1.0 - nu * nu) * w.powi(3) / 12.0;
    let (p_free, p_guided) = (PI * PI * ei / (4.0 * l * l), PI * PI * ei / (l * l));
    assert!(f > p_free && f < p_guided, "wall force {f} N/mm outside the Euler loads [{p_free}, {p_guided}]");
    // the wall has moved 3 mm, 2.5 mm of it against the column
    let straight = e / (1.0 - nu * nu) * (2.5 / l) * w;
    assert!(f < 0.2 * straight, "wall force {f} N/mm not far below the straight column's {straight}");
}
