//! The stabilisation springs of a contact problem: every free node of a particle is tied to
//! an anchor by a spring ζ E a / h² (a the node's tributary area, h the particle's contact
//! length, E its Young's modulus), which keeps particles that touch nothing yet solvable (their
//! rigid-body modes); the energy the springs dissipate is reported and should stay small
//! against the wall work (Abaqus' ALLSD/ALLIE check).

use crate::linalg::BlockMap;

/// Scope of the contact stabilisation springs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Stabilise {
    /// Only the directions (x, y) in which a body is not held by its contacts at the start of
    /// the step (it has no contact pushing it each way); a step that fails is retried with every
    /// dof stabilised before it is cut back.
    Unsupported,
    /// Every free dof of every body, every step.
    #[default]
    All,
}

/// Anchor of the contact stabilisation springs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StabilisationKind {
    /// Anchored at the position extrapolated from the last two converged steps,
    /// u_n + (Δt/Δt_prev)(u_n − u_{n−1}): the springs resist changes of velocity only (like a
    /// nodal mass k Δt²), so particles that move steadily lose no energy to them. The default:
    /// on the 2 × 2 jobs it takes 0.002–0.03 % of the wall work (viscous: 0.5–0.8 %).
    #[default]
    Inertial,
    /// Anchored at the last converged position: the springs resist any motion (a dashpot of
    /// viscosity k Δt); a particle that is let go stops at once.
    Viscous,
}

/// The stabilisation parameters of a model (from the case's `[contact]` table).
#[derive(Clone, Debug, PartialEq)]
pub struct StabilisationParams {
    /// ζ: every free node is tied to its anchor by a spring ζ E a / h² (a tributary area, h
    /// the particle's contact length); 0 turns the springs off.
    pub factor: f64,
    /// Which bodies and directions the springs act on.
    pub scope: Stabilise,
    /// Where the springs are anchored.
    pub kind: StabilisationKind,
    /// Retry a step that fails with the inertial anchor at the same size with the viscous one
    /// before cutting back.
    pub viscous_retry: bool,
    /// On a step smaller than `[time] dt` the springs stiffen as a fixed nodal mass (inertial
    /// anchor: by (dt/Δt)²) or a fixed dashpot (viscous anchor: by dt/Δt) would.
    pub stiffen_on_cutback: bool,
    /// ρ: a spring ρ E a / h² added to the tangent only (not to the residual): it steadies
    /// the Newton iterations of weakly held particles without changing the solution.
    pub regularisation: f64,
}

/// The default ρ of the barrier contact, whose springs are off by default (ζ = 0): the
/// elements' nodal stiffness E a / h² times 1e-8 is added to the diagonal of the tangent only,
/// so a particle that touches nothing, or a rigid-body mode the barrier barely holds, leaves
/// the Newton system regular, while the residual — and so the solution and the reported
/// `stabilisation_energy` — has no springs in it, whatever the step size
/// (docs/robustness.md, twenty-fourth measurement). Springs in the residual (ζ = 1e-8, anchored
/// where each step starts, the default until then) did work that grew with the step: 0.082 %
/// of the wall work on the 256 random polygons of robustness case 12 with steps of 0.015 s,
/// 0.21 % with steps of 0.05 s, and 2.2 % on the 1,024 of case 13 with the larger steps. The
/// tangent-only term at the same size took case 12 to 0.95 in 1,102 Newton iterations against
/// 2,122 with the springs (both with steps grown to `dt_max`).
pub const BARRIER_REGULARISATION: f64 = 1e-8;

impl Default for StabilisationParams {
    fn default() -> Self {
        Self { factor: 1e-5, scope: Stabilise::All, kind: StabilisationKind::Inertial, viscous_retry: false, stiffen_on_cutback: false, regularisation: 0.0 }
    }
}

/// The stabilisation springs of a run: their stiffness per dof, where they are anchored in the
/// current step, and the energy they have dissipated. A force term of the global system like
/// the others: [`Springs::add`] adds its contribution to the internal force and its (diagonal)
/// tangent.
#[derive(Clone, Debug)]
pub struct Springs {
    /// ζ E a / h² per dof (N/mm²), before the `stiffen_on_cutback` factor: the spring of every
    /// dof when it acts (zero without contact).
    pub base: Vec<f64>,
    /// The springs of the current step in the residual: `scale · base`, or 0 where the contacts
    /// hold the body (`scope = "unsupported"`).
    pub k: Vec<f64>,
    /// Tangent-only regularisation ρ E a / h² per dof (N/mm²).
    pub reg: Vec<f64>,
    /// Where the springs of the current step are anchored (displacements, mm).
    pub anchor: Vec<f64>,
    /// Factor of the springs in this step (`stiffen_on_cutback`; 1 otherwise).
    pub scale: f64,
    /// Stabilise every dof in the current step (a retry after a failure).
    pub all: bool,
    /// Anchor the springs at the last converged position in the current step, whatever the
    /// kind says (a retry after a failure with the inertial anchor).
    pub viscous: bool,
    /// Energy dissipated by the springs since the start (N·mm/mm).
    pub energy: f64,
    /// Body of every node.
    pub node_body: Vec<usize>,
}

impl Springs {
    /// The springs of a model with `x0` (reference coordinates), `elements` and their bodies
    /// `elem_body`; `body_e` and `body_h` the Young's modulus and contact length of each body
    /// and `body_nodes` the node range of each. With `contact` false (nothing can touch) every
    /// spring is zero. A node's tributary area a is a quarter of each element it belongs to.
    #[allow(clippy::too_many_arguments)]
    pub fn new(x0: &[[f64; 2]], elements: &[[usize; 4]], elem_body: &[usize], body_e: &[f64], body_h: &[f64], body_nodes: &[std::ops::Range<usize>], params: &StabilisationParams, contact: bool) -> Self {
        let n_dofs = 2 * x0.len();
        let mut base = vec![0.0; n_dofs];
        if contact {
            for (e, el) in elements.iter().enumerate() {
                let b = elem_body[e];
                let a = crate::mesh::polygon_area(el.iter().map(|&n| x0[n])) / 4.0;
                let k = body_e[b] * a / (body_h[b] * body_h[b]);
                for &n in el {
                    base[2 * n] += k;
                    base[2 * n + 1] += k;
                }
            }
        }
        // base nodal stiffness E a / h² → stabilisation ζ·base (residual and tangent) and
        // regularisation ρ·base (tangent only)
        let reg: Vec<f64> = base.iter().map(|k| k * params.regularisation).collect();
        base.iter_mut().for_each(|k| *k *= params.factor);
        let mut node_body = vec![0; x0.len()];
        for (b, r) in body_nodes.iter().enumerate() {
            node_body[r.clone()].fill(b);
        }
        Self { k: base.clone(), base, reg, anchor: vec![0.0; n_dofs], scale: 1.0, all: false, viscous: false, energy: 0.0, node_body }
    }

    /// Set up the springs of a solve that ends at `t_n + dt` from the converged `u_n` (and the
    /// one before, `u_prev`, reached in `dt_prev`): the anchor (`u_n` extrapolated by the last
    /// velocity for the inertial kind, `u_n` itself for the viscous kind or a retry), the
    /// `stiffen_on_cutback` factor for a step cut below the case's `dt_case` (a fixed nodal mass
    /// k ∝ 1/Δt², or dashpot k ∝ 1/Δt), and which dofs carry a spring in the residual: all, or
    /// only the directions of the bodies the committed contacts do not hold (`held`, per body,
    /// computed by the caller when asked for). `dt = 0` is a re-equilibration in place.
    #[allow(clippy::too_many_arguments)]
    pub fn prepare(&mut self, params: &StabilisationParams, u_n: &[f64], u_prev: &[f64], dt: f64, dt_prev: f64, dt_case: f64, held: impl FnOnce() -> Vec<[bool; 2]>) {
        // anchor of the springs: the last converged position, or its extrapolation
        let inertial = params.kind == StabilisationKind::Inertial && !self.viscous;
        let s = if inertial && dt_prev > 0.0 { dt / dt_prev } else { 0.0 };
        for d in 0..self.anchor.len() {
            self.anchor[d] = u_n[d] + s * (u_n[d] - u_prev[d]);
        }
        self.scale = 1.0;
        if params.stiffen_on_cutback && dt > 0.0 && dt < dt_case {
            let ratio = dt_case / dt;
            self.scale = if inertial { ratio * ratio } else { ratio };
        }
        let scale = self.scale;
        if self.all || params.scope == Stabilise::All {
            for (k, b) in self.k.iter_mut().zip(&self.base) {
                *k = scale * b;
            }
        } else {
            let held = held();
            for (d, k) in self.k.iter_mut().enumerate() {
                *k = if held[self.node_body[d / 2]][d % 2] { 0.0 } else { scale * self.base[d] };
            }
        }
    }

    /// Add the springs at displacements `u` to the internal force `f_int` (all dofs) and, with
    /// a tangent (matrix values and the position of every dof's diagonal entry), their
    /// stiffness `scale · base` and the regularisation to the diagonal. A dof the contacts
    /// hold has no spring in the residual but keeps it in the tangent, where it only steadies
    /// the iterations; the regularisation changes the Newton path, not the solution.
    pub fn add(&self, u: &[f64], f_int: &mut [f64], mut tangent: Option<(&mut [f64], &BlockMap)>) {
        for (d, (&k, &kr)) in self.k.iter().zip(&self.reg).enumerate() {
            if k > 0.0 {
                f_int[d] += k * (u[d] - self.anchor[d]);
            }
            let kt = self.scale * self.base[d] + kr;
            if let Some((values, diag)) = tangent.as_mut() {
                if kt > 0.0 {
                    diag.add(values, d, &[kt]);
                }
            }
        }
    }

    /// The work done against the springs over a step from `u_old` to `u_new`: their force at
    /// the end of the step times the increment (N·mm/mm), which [`Springs::energy`] sums.
    pub fn work(&self, u_new: &[f64], u_old: &[f64]) -> f64 {
        self.k.iter().enumerate().map(|(d, k)| k * (u_new[d] - self.anchor[d]) * (u_new[d] - u_old[d])).sum()
    }
}
