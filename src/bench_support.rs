//! Fixtures shared by the criterion benchmarks in `benches/` (not part of the stable API).

use crate::assembly::{number_equations, Assembler, ElementFields};
use crate::case::Formulation;
use crate::element::Volumetric;
use crate::linalg::CsrMatrix;
use crate::material::{ConstitutiveLaw, Elastic, HardeningTable, J2Plastic, MatState, Material, TimeIncrement};
use crate::mesh::shapes;
use crate::model::Model;

/// Which law the fixture uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Law {
    /// Hencky elasticity, E = 64 100 MPa, ν = 0.3.
    Elastic,
    /// J2 with the paper's Table 1 hardening, deformed into the plastic range.
    J2,
}

/// An n × n block of 1 mm elements with its bottom edge fixed, deformed homogeneously by
/// F = diag(1.01, 0.99) (1 % strain: every Gauss point of the J2 block is plastic).
pub struct Fixture {
    pub model: Model,
    pub assembler: Assembler,
    pub kk: CsrMatrix,
    pub f_int: Vec<f64>,
    pub fields: ElementFields,
    pub old: Vec<[MatState; 4]>,
    pub vol: Vec<Volumetric>,
    pub u: Vec<f64>,
    pub pool: Option<rayon::ThreadPool>,
}

pub fn assembly_fixture(n: usize, law: Law, threads: usize) -> Fixture {
    let mesh = shapes::rectangle([0.0, 0.0], n as f64, n as f64, n, n);
    let (e, nu) = (64100.0, 0.3);
    let material = match law {
        Law::Elastic => Material::Elastic(Elastic::new(e, nu)),
        Law::J2 => Material::J2(J2Plastic::new(
            e,
            nu,
            HardeningTable::from_total_strain(e, &crate::material::hardening::aluminium_250c()).expect("Table 1"),
        )),
    };
    let bottom = mesh.node_set("bottom").unwrap_or_default();
    let ne = mesh.elements.len();
    let model = Model {
        title: "benchmark block".into(),
        formulation: Formulation::UpdatedLagrangian,
        plane_stress: false,
        element: crate::element::ElementKind::Q1P0,
        loading: crate::loading::Loading {
            prescribed: bottom
                .iter()
                .flat_map(|&n| [2 * n, 2 * n + 1])
                .map(|dof| crate::loading::PrescribedDof { dof, value: 0.0, amplitude: 0 })
                .collect(),
            amplitudes: vec![crate::loading::Amplitude::Constant],
            t_end: 1.0,
            ..Default::default()
        },
        contact: Default::default(),
        stabilisation: Default::default(),
        stop: Default::default(),
        remesh: Default::default(),
        materials: vec![material.clone()],
        densities: vec![2.7e-9],
        x0: mesh.nodes.clone(),
        elements: mesh.elements.clone(),
        elem_material: vec![0; ne],
        elem_body: vec![0; ne],
        probes: Vec::new(),
        bodies: vec![crate::model::Body { name: "block".into(), contact_h: crate::model::Body::mean_element_size(&mesh), mesh, material: 0, node_offset: 0, elem_offset: 0, mesh_size: 1.0 }],
        reaction_groups: vec![],
        displacement_groups: vec![],
        whole: None,
    };
    let (eq, n_free) = number_equations(model.n_dofs(), model.loading.prescribed.iter().map(|p| p.dof));
    let (assembler, kk) = Assembler::new(&model, eq, n_free);
    let u = model.x0.iter().flat_map(|p| [0.01 * p[0], -0.01 * p[1]]).collect();
    let kappa = material.bulk_modulus().unwrap_or(1e3 * material.shear_modulus());
    let pool = (threads > 1).then(|| rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool"));
    Fixture {
        f_int: vec![0.0; model.n_dofs()],
        fields: ElementFields::new(ne),
        old: vec![[MatState::default(); 4]; ne],
        vol: vec![Volumetric { kappa, lambda: 0.0 }; ne],
        u,
        pool,
        assembler,
        kk,
        model,
    }
}

impl Fixture {
    /// Internal force and tangent of every element; returns ‖f_int‖₁ so nothing is optimised away.
    pub fn assemble(&mut self) -> f64 {
        self.assembler
            .assemble(
                &self.model,
                &self.u,
                &self.old,
                &vec![[0.0; crate::element::N_ENH]; self.old.len()],
                &self.vol,
                None,
                TimeIncrement { time: 1.0, dt: 1.0 },
                Some(&mut self.kk),
                &mut self.f_int,
                &mut self.fields,
                self.pool.as_ref(),
            )
            .expect("assembly");
        self.f_int.iter().map(|v| v.abs()).sum()
    }

    /// The assembled tangent and a right-hand side (the free part of the internal force).
    pub fn system(&self) -> (&CsrMatrix, Vec<f64>) {
        let mut b = vec![0.0; self.assembler.n_free];
        for (d, &q) in self.assembler.eq.iter().enumerate() {
            if q != crate::assembly::FIXED {
                b[q] = self.f_int[d] + 1e-3;
            }
        }
        (&self.kk, b)
    }
}

/// Case text of elastic aluminium particles (E = 64 100 MPa, ν = 0.3, material "m") described by
/// `particles` (a `[[grids]]` or `[[packings]]` table) in a square die of side `side` mm whose
/// four walls move in at `velocity` mm/s, one time step of 0.1 s; `extra` is appended.
fn elastic_die_case(title: &str, particles: &str, side: f64, velocity: f64, extra: &str) -> String {
    let walls: String = [("left", 0.0), ("right", side), ("bottom", 0.0), ("top", side)]
        .iter()
        .map(|(s, p)| format!("[[walls]]\nside = \"{s}\"\nposition = {p:?}\nvelocity = {velocity:?}\n"))
        .collect();
    format!(
        r#"title = "{title}"
[[materials]]
name = "m"
model = "elastic"
youngs_modulus = 64100.0
poisson_ratio = 0.3
{particles}
[time]
end = 1.0
dt = 0.1
{walls}{extra}"#
    )
}

/// Case text of an `n × n` grid of elastic aluminium discs (E = 64 100 MPa, ν = 0.3) at solid
/// ratio `solid_ratio` in a square die of side `side` mm whose four walls move in at 10 mm/s,
/// meshed at `mesh_size`, one time step of 0.1 s; `extra` is appended (further tables, such as
/// `[contact]` or `[solver]`).
pub fn disc_grid_case(n: usize, side: f64, solid_ratio: f64, mesh_size: f64, extra: &str) -> String {
    let grid = format!("[[grids]]\nmaterial = \"m\"\nnx = {n}\nny = {n}\nshape = \"disc\"\nsolid_ratio = {solid_ratio}\nmesh_size = {mesh_size}");
    elastic_die_case("benchmark disc grid", &grid, side, 10.0, extra)
}

/// The stiffness-like matrix of an `n × n` grid of elastic discs (E = 64 100 MPa, ν = 0.3) at a
/// solid ratio of 0.78 (neighbours almost touch) in a 100 mm die, meshed at `mesh_size`, with
/// every degree of freedom free:
/// the element tangent at u = 0, plus "contact" springs (stiffness 0.1 × the mean diagonal,
/// the pattern of a penalty contact tangent) joining every boundary node to the boundary nodes
/// of other discs within 0.15 × the disc pitch (contact zones of a compacted packing), plus
/// 1e-3 × the mean diagonal on the diagonal (a mass term; removes the rigid-body modes), so the
/// matrix is symmetric positive definite.
pub fn particle_grid_tangent(n: usize, mesh_size: f64) -> CsrMatrix {
    packing_tangent(&disc_grid_case(n, 100.0, 0.78, mesh_size, ""), 0.15 * 100.0 / n as f64)
}

/// Case text of `count` random polydisperse elastic aluminium discs (radii uniform between r
/// and 2r, `[[packings]] kind = "discs"`, seed 29) at solid ratio 0.70 in a square die of side
/// `side` mm with fixed walls, meshed at `mesh_size` (the packing of the 1,024-disc gauge of
/// docs/performance.md at `count` = 1024, `side` = 320, `mesh_size` = 2).
pub fn random_discs_case(count: usize, side: f64, mesh_size: f64) -> String {
    let packing = format!(
        "[[packings]]\nkind = \"discs\"\ncount = {count}\nseed = 29\nsolid_ratio = 0.70\nmaterial = \"m\"\nsizes = {{ distribution = \"uniform\", ratio = 2.0 }}\nmesh_size = {mesh_size}"
    );
    elastic_die_case("benchmark random discs", &packing, side, 0.0, "")
}

/// The stiffness-like matrix of the particles of case `text` with every degree of freedom
/// free: the element tangent at u = 0, plus "contact" springs (stiffness 0.1 × the mean
/// diagonal, the pattern of a contact tangent) joining every boundary node to the boundary
/// nodes of other particles within `reach` mm, plus 1e-3 × the mean diagonal on the diagonal
/// (a mass term; removes the rigid-body modes), so the matrix is symmetric positive definite.
/// A small `reach` gives a loose packing's nearly block-diagonal tangent.
pub fn packing_tangent(text: &str, reach: f64) -> CsrMatrix {
    let case = crate::case::parse(text, std::path::Path::new(".")).expect("benchmark case");
    let model = Model::from_case(&case).expect("benchmark model");
    let (eq, n_free) = number_equations(model.n_dofs(), std::iter::empty());
    let (mut assembler, mut kk) = Assembler::new(&model, eq, n_free);
    let ne = model.elements.len();
    let material = &model.materials[0];
    let kappa = material.bulk_modulus().unwrap_or(1e3 * material.shear_modulus());
    let mut f_int = vec![0.0; model.n_dofs()];
    assembler
        .assemble(
            &model,
            &vec![0.0; model.n_dofs()],
            &vec![[MatState::default(); 4]; ne],
            &vec![[0.0; crate::element::N_ENH]; ne],
            &vec![Volumetric { kappa, lambda: 0.0 }; ne],
            None,
            TimeIncrement { time: 1.0, dt: 1.0 },
            Some(&mut kk),
            &mut f_int,
            &mut ElementFields::new(ne),
            None,
        )
        .expect("assembly");
    // Boundary nodes of every body (global numbers) and the node pairs within reach.
    let boundary: Vec<Vec<usize>> = model
        .bodies
        .iter()
        .map(|b| {
            let mut v: Vec<usize> = b.mesh.boundary.iter().flatten().map(|&l| l + b.node_offset).collect();
            v.sort_unstable();
            v.dedup();
            v
        })
        .collect();
    // (each body's bounding box, to skip the pairs of bodies farther apart than `reach`)
    let boxes: Vec<[f64; 4]> = boundary
        .iter()
        .map(|b| b.iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |m, &i| {
            let p = model.x0[i];
            [m[0].min(p[0]), m[1].min(p[1]), m[2].max(p[0]), m[3].max(p[1])]
        }))
        .collect();
    let mut pairs = Vec::new();
    for (a, ba) in boundary.iter().enumerate() {
        for (k, bb) in boundary.iter().enumerate().skip(a + 1) {
            let (p, q) = (boxes[a], boxes[k]);
            if p[0] > q[2] + reach || q[0] > p[2] + reach || p[1] > q[3] + reach || q[1] > p[3] + reach {
                continue;
            }
            for &i in ba {
                for &j in bb {
                    let (p, q) = (model.x0[i], model.x0[j]);
                    if (p[0] - q[0]).hypot(p[1] - q[1]) <= reach {
                        pairs.push((i, j));
                    }
                }
            }
        }
    }
    let nd = kk.nrows;
    let mut rows: Vec<Vec<usize>> = (0..nd).map(|r| kk.col_idx[kk.row_ptr[r]..kk.row_ptr[r + 1]].to_vec()).collect();
    for &(i, j) in &pairs {
        for c in 0..2 {
            rows[2 * i + c].push(2 * j + c);
            rows[2 * j + c].push(2 * i + c);
        }
    }
    for r in rows.iter_mut() {
        r.sort_unstable();
        r.dedup();
    }
    let mut a = CsrMatrix::from_rows(nd, &rows);
    for r in 0..nd {
        for k in kk.row_ptr[r]..kk.row_ptr[r + 1] {
            let p = a.find(r, kk.col_idx[k]).expect("same pattern");
            a.values[p] += kk.values[k];
        }
    }
    let mean_diag = kk.diagonal().iter().sum::<f64>() / nd as f64;
    let spring = 0.1 * mean_diag;
    for &(i, j) in &pairs {
        for c in 0..2 {
            let (u, v) = (2 * i + c, 2 * j + c);
            for (r, s, val) in [(u, u, spring), (v, v, spring), (u, v, -spring), (v, u, -spring)] {
                let p = a.find(r, s).expect("spring entry");
                a.values[p] += val;
            }
        }
    }
    for r in 0..nd {
        let p = a.find(r, r).expect("diagonal");
        a.values[p] += 1e-3 * mean_diag;
    }
    a
}

/// The contact pattern of an `n × n` disc grid at two configurations: the reference one
/// (neighbours at solid ratio 0.78, almost touching) and the same with every other disc moved
/// by 0.4 element sizes along y (the nodes of the contact zones face other segments: other
/// pairs). Switching the assembler between the two pair sets is a change of contact pairs.
pub struct PairChange {
    pub model: Model,
    pub assembler: Assembler,
    pub kk: CsrMatrix,
    /// The dofs of every frozen pair in each configuration.
    pub pairs: [Vec<Vec<usize>>; 2],
}

/// [`PairChange`] of an `n × n` grid of discs meshed at `mesh_size` in a 100 n mm die.
pub fn pair_change_fixture(n: usize, mesh_size: f64) -> PairChange {
    let side = 100.0 * n as f64;
    let text = disc_grid_case(n, side, 0.78, mesh_size, "[contact]\nsearch_distance = 5.0\n");
    let case = crate::case::parse(&text, std::path::Path::new(".")).expect("benchmark case");
    let model = Model::from_case(&case).expect("benchmark model");
    let mut contact = model.contact_problem().expect("a contact problem");
    let walls = model.wall_planes(0.0);
    let mut moved = model.x0.clone();
    for body in model.bodies.iter().skip(1).step_by(2) {
        for p in &mut moved[body.node_offset..body.node_offset + body.mesh.n_nodes()] {
            p[1] += 0.4 * mesh_size;
        }
    }
    contact.select_pairs(&model.x0, &walls);
    let a = contact.pair_dof_lists();
    contact.select_pairs(&moved, &walls);
    let b = contact.pair_dof_lists();
    assert_ne!(a, b, "the two configurations must have other pairs");
    let (eq, n_free) = number_equations(model.n_dofs(), std::iter::empty());
    let (assembler, kk) = Assembler::new(&model, eq, n_free);
    PairChange { model, assembler, kk, pairs: [a, b] }
}

impl PairChange {
    /// Switch the pattern to pair set `k` (0 or 1) the incremental way (what a step whose
    /// pairs changed does); returns the number of entries.
    pub fn switch(&mut self, k: usize) -> usize {
        self.assembler.set_terms(&mut self.kk, &self.pairs[k], &[]);
        self.kk.nnz()
    }

    /// Rebuild the assembler and its pattern from the mesh for pair set `k` (what every change
    /// of pairs cost before the pattern was updated incrementally); returns the entries.
    pub fn rebuild(&mut self, k: usize) -> usize {
        let (mut a, mut kk) = Assembler::new(&self.model, self.assembler.eq.clone(), self.assembler.n_free);
        a.set_terms(&mut kk, &self.pairs[k], &[]);
        self.assembler = a;
        self.kk = kk;
        self.kk.nnz()
    }
}

/// The Hessian Jᵀ K J of a pair whose first side is the point x = (1 − ξ) c + ξ d of an edge
/// (c, d) and whose energy has the Hessian `k` in x − a and b − a (a, b the other edge): dofs
/// `[c, d, a, b]`, each x then y, as the barrier's edge points have it (for the projection's
/// benchmark and its unit test).
pub fn edge_point_hessian(k: &[[f64; 4]; 4], xi: f64) -> [[f64; 8]; 8] {
    // J: the rows (x − a) and (b − a) in each direction
    let mut jm = [[0.0; 8]; 4];
    for c in 0..2 {
        jm[c][c] = 1.0 - xi;
        jm[c][2 + c] = xi;
        jm[c][4 + c] = -1.0;
        jm[2 + c][4 + c] = -1.0;
        jm[2 + c][6 + c] = 1.0;
    }
    std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|a| (0..4).map(|b| jm[a][i] * k[a][b] * jm[b][j]).sum::<f64>()).sum()))
}
