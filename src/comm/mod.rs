//! The collective operations of the processes of a run (MPI ranks), behind one small trait
//! ([`Collective`]): what the solver driver, the distributed linear solvers and the output
//! need, and nothing else, and the index maps of distributed vectors ([`IndexMap`]: owned
//! indices and ghosts, and the scatters between them). [`Serial`] is one process (every operation the identity);
//! [`mpi::MpiCollective`] is MPI's world communicator (feature `mpi`). A leaf module: it
//! knows nothing of the model or the physics, which never see it (parallelism is passed in).

pub mod index_map;
#[cfg(feature = "mpi")]
pub mod mpi;

pub use index_map::{IndexMap, IndexMapError};

use std::sync::Arc;

/// The collective operations of a group of processes (MPI ranks), as the solver driver uses
/// them. Every process must call the same operations in the same order with buffers of the
/// same length. Rank 0 is the root.
pub trait Collective: Send + Sync {
    /// This process's rank (0 ≤ rank < size).
    fn rank(&self) -> usize;
    /// Number of processes.
    fn size(&self) -> usize;
    /// Whether this is rank 0 (which solves the linear systems and writes the results).
    fn is_root(&self) -> bool {
        self.rank() == 0
    }
    /// Element-wise sum over the processes; the result on every process.
    fn sum_in_place(&self, x: &mut [f64]);
    /// Element-wise sum over the processes; the result on rank 0 only (`x` is unspecified
    /// on the other ranks afterwards).
    fn sum_to_root(&self, x: &mut [f64]);
    /// Rank 0's `x` on every process.
    fn broadcast(&self, x: &mut [f64]);
    /// Wait until every process has reached this call, sleeping between polls instead of
    /// spinning (a barrier for the places where the others wait for rank 0's work, so that
    /// their cores are free meanwhile). Serial: nothing.
    fn idle_barrier(&self) {}
    /// Every process's `local` values concatenated in rank order, on every process (the
    /// lengths may differ between processes).
    fn all_gather_varcount(&self, local: &[f64]) -> Vec<f64>;
    /// Every process's `local` values concatenated in rank order, on rank 0; empty on the
    /// others.
    fn gather_varcount_to_root(&self, local: &[f64]) -> Vec<f64>;
    /// A personalised exchange (all-to-all with counts per pair): `send[r]` goes to rank `r`
    /// (`send` has one buffer per process, empty ones included); the result's `r`-th buffer
    /// is what rank `r` sent to this one. The ghost exchanges of [`crate::parallel`] go
    /// through it.
    fn exchange(&self, send: &[Vec<f64>]) -> Vec<Vec<f64>>;
    /// Smallest `x` over the processes, on every process.
    fn min_u64(&self, x: u64) -> u64;
    /// Largest `x` over the processes, on every process.
    fn max(&self, x: f64) -> f64;
    /// End every process with exit code `code`, for an error one process meets alone (the
    /// others would wait for it in the next collective operation). Does nothing on one
    /// process.
    fn abort_all(&self, _code: i32) {}
}

/// One process: every operation is the identity.
#[derive(Clone, Copy, Debug, Default)]
pub struct Serial;

impl Collective for Serial {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn sum_in_place(&self, _x: &mut [f64]) {}
    fn sum_to_root(&self, _x: &mut [f64]) {}
    fn broadcast(&self, _x: &mut [f64]) {}
    fn all_gather_varcount(&self, local: &[f64]) -> Vec<f64> {
        local.to_vec()
    }
    fn gather_varcount_to_root(&self, local: &[f64]) -> Vec<f64> {
        local.to_vec()
    }
    fn exchange(&self, send: &[Vec<f64>]) -> Vec<Vec<f64>> {
        send.to_vec()
    }
    fn min_u64(&self, x: u64) -> u64 {
        x
    }
    fn max(&self, x: f64) -> f64 {
        x
    }
}

/// The collective of this process: MPI's world when the `mpi` feature is on and the process was
/// started by an MPI launcher (`mpirun`, `srun`, …), otherwise [`Serial`]. Call it once, early
/// (MPI initialises once per process); MPI finalises when the last clone of the returned `Arc`
/// is dropped.
pub fn launch() -> Arc<dyn Collective> {
    #[cfg(feature = "mpi")]
    if let Some(m) = mpi::MpiCollective::init_if_launched() {
        return Arc::new(m);
    }
    Arc::new(Serial)
}

