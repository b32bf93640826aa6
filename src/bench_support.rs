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
        element: crate::element::ElementKind::Q1P0,
        walls: vec![],
        contact: Default::default(),
        stop: Default::default(),
        remesh: Default::default(),
        materials: vec![material.clone()],
        densities: vec![2.7e-9],
        x0: mesh.nodes.clone(),
        elements: mesh.elements.clone(),
        elem_material: vec![0; ne],
        elem_body: vec![0; ne],
        bodies: vec![crate::model::Body { name: "block".into(), mesh, material: 0, node_offset: 0, elem_offset: 0, mesh_size: 1.0 }],
        prescribed: bottom
            .iter()
            .flat_map(|&n| [2 * n, 2 * n + 1])
            .map(|dof| crate::model::PrescribedDof { dof, value: 0.0, amplitude: 0 })
            .collect(),
        loads: vec![],
        amplitudes: vec![crate::case::Amplitude::Constant],
        reaction_groups: vec![],
        displacement_groups: vec![],
        t_end: 1.0,
    };
    let (eq, n_free) = number_equations(model.n_dofs(), model.prescribed.iter().map(|p| p.dof));
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
