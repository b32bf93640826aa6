//! [`Collective`] over MPI (rsmpi), compiled with the `mpi` feature.

use super::Collective;
use mpi::collective::SystemOperation;
use mpi::datatype::{Partition, PartitionMut};
use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;

/// Offsets of consecutive blocks of the given lengths, and their total.
fn displacements(counts: &[Count]) -> (Vec<Count>, usize) {
    let mut displs = Vec::with_capacity(counts.len());
    let mut at: Count = 0;
    for &c in counts {
        displs.push(at);
        at += c;
    }
    (displs, at as usize)
}

/// MPI's world communicator. Owns the MPI environment: MPI finalises when it is dropped.
pub struct MpiCollective {
    // (dropped before the universe: fields drop in declaration order)
    world: SimpleCommunicator,
    _universe: Universe,
    rank: usize,
    size: usize,
}

// SAFETY: MPI is initialised with `Threading::Funneled` and the driver calls these operations
// from the thread that initialised it only (the rayon workers of the assembly never do); the
// handles are plain integers/pointers owned by the MPI library.
unsafe impl Send for MpiCollective {}
unsafe impl Sync for MpiCollective {}

/// Environment variables one of which MPI launchers set in every process they start (Open MPI,
/// MPICH/Hydra, PMIx, Slurm's PMI).
const LAUNCHER_VARIABLES: [&str; 5] = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS", "PMI_RANK"];

impl MpiCollective {
    /// Initialise MPI when this process was started by an MPI launcher (a process started
    /// directly stays serial and never touches MPI). `None` if it was not, or MPI cannot
    /// start or was started already.
    pub fn init_if_launched() -> Option<Self> {
        if !LAUNCHER_VARIABLES.iter().any(|v| std::env::var_os(v).is_some()) {
            return None;
        }
        let (universe, _threading) = mpi::initialize_with_threading(mpi::Threading::Funneled)?;
        let world = universe.world();
        let (rank, size) = (world.rank() as usize, world.size() as usize);
        Some(Self { world, _universe: universe, rank, size })
    }
}

impl Collective for MpiCollective {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn sum_in_place(&self, x: &mut [f64]) {
        if self.size > 1 && !x.is_empty() {
            let send = x.to_vec();
            self.world.all_reduce_into(&send[..], x, SystemOperation::sum());
        }
    }

    fn sum_to_root(&self, x: &mut [f64]) {
        if self.size <= 1 || x.is_empty() {
            return;
        }
        let root = self.world.process_at_rank(0);
        if self.rank == 0 {
            let send = x.to_vec();
            root.reduce_into_root(&send[..], x, SystemOperation::sum());
        } else {
            root.reduce_into(&x[..], SystemOperation::sum());
        }
    }

    fn broadcast(&self, x: &mut [f64]) {
        if self.size > 1 && !x.is_empty() {
            self.world.process_at_rank(0).broadcast_into(x);
        }
    }

    fn idle_barrier(&self) {
        if self.size <= 1 {
            return;
        }
        // a non-blocking barrier polled with naps growing from 10 µs to 200 µs: a process that
        // arrives last finds it complete at once, one that waits for a factorisation of tens of
        // milliseconds or more wakes at most 0.2 ms late and leaves its core to other threads
        let mut request = self.world.immediate_barrier();
        let mut nap = std::time::Duration::from_micros(10);
        loop {
            match request.test() {
                Ok(_) => return,
                Err(pending) => {
                    request = pending;
                    std::thread::sleep(nap);
                    nap = (2 * nap).min(std::time::Duration::from_micros(200));
                }
            }
        }
    }

    fn all_gather_varcount(&self, local: &[f64]) -> Vec<f64> {
        if self.size <= 1 {
            return local.to_vec();
        }
        let n = local.len() as Count;
        let mut counts = vec![0 as Count; self.size];
        self.world.all_gather_into(&n, &mut counts[..]);
        let (displs, total) = displacements(&counts);
        let mut out = vec![0.0; total];
        let mut part = PartitionMut::new(&mut out[..], &counts[..], &displs[..]);
        self.world.all_gather_varcount_into(local, &mut part);
        out
    }

    fn gather_varcount_to_root(&self, local: &[f64]) -> Vec<f64> {
        if self.size <= 1 {
            return local.to_vec();
        }
        let root = self.world.process_at_rank(0);
        let n = local.len() as Count;
        if self.rank != 0 {
            root.gather_into(&n);
            root.gather_varcount_into(local);
            return Vec::new();
        }
        let mut counts = vec![0 as Count; self.size];
        root.gather_into_root(&n, &mut counts[..]);
        let (displs, total) = displacements(&counts);
        let mut out = vec![0.0; total];
        let mut part = PartitionMut::new(&mut out[..], &counts[..], &displs[..]);
        root.gather_varcount_into_root(local, &mut part);
        out
    }

    fn exchange(&self, send: &[Vec<f64>]) -> Vec<Vec<f64>> {
        assert_eq!(send.len(), self.size, "one send buffer per process");
        if self.size <= 1 {
            return send.to_vec();
        }
        let send_counts: Vec<Count> = send.iter().map(|b| b.len() as Count).collect();
        let mut recv_counts = vec![0 as Count; self.size];
        self.world.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
        let (send_displs, _) = displacements(&send_counts);
        let (recv_displs, total) = displacements(&recv_counts);
        let flat: Vec<f64> = send.concat();
        let mut out = vec![0.0; total];
        {
            let part = Partition::new(&flat[..], &send_counts[..], &send_displs[..]);
            let mut recv = PartitionMut::new(&mut out[..], &recv_counts[..], &recv_displs[..]);
            self.world.all_to_all_varcount_into(&part, &mut recv);
        }
        recv_counts.iter().zip(&recv_displs).map(|(&c, &d)| out[d as usize..(d + c) as usize].to_vec()).collect()
    }

    fn min_u64(&self, x: u64) -> u64 {
        let mut out = x;
        if self.size > 1 {
            self.world.all_reduce_into(&x, &mut out, SystemOperation::min());
        }
        out
    }

    fn abort_all(&self, code: i32) {
        if self.size > 1 {
            self.world.abort(code);
        }
    }

    fn max(&self, x: f64) -> f64 {
        let mut out = x;
        if self.size > 1 {
            self.world.all_reduce_into(&x, &mut out, SystemOperation::max());
        }
        out
    }
}
