//! A distributed index set: which process owns which indices (nodes) of a global numbering, and
//! the copies (ghosts) a process holds of other processes' indices — the shape of dolfinx's
//! `IndexMap` and of PETSc's ghosted vectors.
//!
//! Every process owns one contiguous range of the global numbering, in rank order (process 0
//! the first `n_owned` indices, and so on). A process's local numbering puts its owned indices
//! first (local `i` is global `start + i`) and its ghosts after them (local `n_owned + k` is
//! global `ghosts[k]`). Two exchanges move values between the owners and the copies, for
//! vectors of `bs` values per index (2 per node: its x and y dofs):
//! - [`IndexMap::forward`]: every ghost takes its owner's value (after an update was computed
//!   on the owned indices);
//! - [`IndexMap::reverse_add`]: every ghost's value is added to its owner's (contributions a
//!   process assembled into indices it does not own: the element and contact terms at the edge
//!   of its part), and the ghosts are then zero.
//!
//! The lists of what goes where are agreed once, when the map is made (one exchange of the
//! ghosts' global indices with their owners); each scatter is then one
//! [`Collective::exchange`]. (A leaf like the rest of `comm`: it knows indices, not nodes; a
//! process's part of a model, [`crate::parallel::part`], makes the map of its nodes.)

use super::Collective;
use std::sync::Arc;

/// Why an index map cannot be made.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum IndexMapError {
    #[error("ghost {ghost} is not a global index (there are {n_global})")]
    OutOfRange { ghost: usize, n_global: usize },
    #[error("ghost {ghost} is owned by this process (rank {rank}): a ghost is another process's index")]
    OwnGhost { ghost: usize, rank: usize },
    #[error("ghost {ghost} is listed twice")]
    Repeated { ghost: usize },
}

/// The ownership of a distributed index set and the exchanges between owners and ghosts (see
/// the module docs).
pub struct IndexMap {
    comm: Arc<dyn Collective>,
    /// First global index of each process's range, and the total (`size + 1` entries).
    ranges: Vec<usize>,
    /// Global index of each ghost (local index `n_owned + k`).
    ghosts: Vec<usize>,
    /// Owning process of each ghost.
    ghost_owner: Vec<usize>,
    /// Per process: the owned local indices whose values it holds as ghosts, in the order it
    /// lists them.
    send: Vec<Vec<usize>>,
    /// Per process: the positions `k` of the ghosts it owns, in the order of `send` there.
    recv: Vec<Vec<usize>>,
}

impl IndexMap {
    /// The map of `n_owned` indices owned here (the processes' ranges follow each other in rank
    /// order) and copies of the global indices `ghosts` (other processes'), local
    /// `n_owned + k` for `ghosts[k]`. Collective: every process calls it.
    ///
    /// # Errors
    /// A ghost that is not a global index, is owned here, or is listed twice — on the process
    /// that lists it; the others still complete the call (the lists are exchanged either way).
    pub fn new(comm: Arc<dyn Collective>, n_owned: usize, ghosts: Vec<usize>) -> Result<Self, IndexMapError> {
        let size = comm.size();
        let rank = comm.rank();
        let counts = comm.all_gather_varcount(&[n_owned as f64]);
        let mut ranges = Vec::with_capacity(size + 1);
        let mut at = 0;
        ranges.push(0);
        for c in &counts {
            at += *c as usize;
            ranges.push(at);
        }
        let n_global = at;
        let mut problem = None;
        let mut seen = std::collections::HashSet::with_capacity(ghosts.len());
        let mut ghost_owner = Vec::with_capacity(ghosts.len());
        for &g in &ghosts {
            let owner = if g >= n_global { None } else { Some(ranges.partition_point(|&s| s <= g) - 1) };
            match owner {
                None => problem = problem.or(Some(IndexMapError::OutOfRange { ghost: g, n_global })),
                Some(o) if o == rank => problem = problem.or(Some(IndexMapError::OwnGhost { ghost: g, rank })),
                Some(_) if !seen.insert(g) => problem = problem.or(Some(IndexMapError::Repeated { ghost: g })),
                Some(_) => {}
            }
            ghost_owner.push(owner.unwrap_or(rank));
        }
        // ask every owner for its indices (a process with a bad list asks for nothing)
        let mut recv = vec![Vec::new(); size];
        if problem.is_none() {
            for (k, &o) in ghost_owner.iter().enumerate() {
                recv[o].push(k);
            }
        }
        let requests: Vec<Vec<f64>> = recv.iter().map(|ks| ks.iter().map(|&k| ghosts[k] as f64).collect()).collect();
        let asked = comm.exchange(&requests);
        let start = ranges[rank];
        let send = asked.iter().map(|gs| gs.iter().map(|&g| g as usize - start).collect()).collect();
        if let Some(e) = problem {
            return Err(e);
        }
        Ok(Self { comm, ranges, ghosts, ghost_owner, send, recv })
    }

    /// The processes of the map.
    pub fn comm(&self) -> &dyn Collective {
        self.comm.as_ref()
    }

    /// The processes of the map, to share.
    pub fn comm_arc(&self) -> Arc<dyn Collective> {
        self.comm.clone()
    }

    /// Indices owned here.
    pub fn n_owned(&self) -> usize {
        let r = self.comm.rank();
        self.ranges[r + 1] - self.ranges[r]
    }

    /// Owned and ghost indices: the length of a local vector (times its block size).
    pub fn n_local(&self) -> usize {
        self.n_owned() + self.ghosts.len()
    }

    /// Indices over all processes.
    pub fn n_global(&self) -> usize {
        *self.ranges.last().unwrap_or(&0)
    }

    /// First global index owned here.
    pub fn start(&self) -> usize {
        self.ranges[self.comm.rank()]
    }

    /// Global index of each ghost.
    pub fn ghosts(&self) -> &[usize] {
        &self.ghosts
    }

    /// Owning process of each ghost.
    pub fn ghost_owners(&self) -> &[usize] {
        &self.ghost_owner
    }

    /// Global index of local index `i`.
    pub fn global(&self, i: usize) -> usize {
        let n = self.n_owned();
        if i < n {
            self.start() + i
        } else {
            self.ghosts[i - n]
        }
    }

    /// Give every ghost its owner's value: `x` holds `bs` values per local index (owned first,
    /// then ghosts). Collective.
    pub fn forward(&self, x: &mut [f64], bs: usize) {
        debug_assert_eq!(x.len(), self.n_local() * bs);
        let out: Vec<Vec<f64>> = self.send.iter().map(|is| is.iter().flat_map(|&i| x[i * bs..(i + 1) * bs].iter().copied()).collect()).collect();
        let got = self.comm.exchange(&out);
        let n = self.n_owned();
        for (ks, vals) in self.recv.iter().zip(&got) {
            for (j, &k) in ks.iter().enumerate() {
                x[(n + k) * bs..(n + k + 1) * bs].copy_from_slice(&vals[j * bs..(j + 1) * bs]);
            }
        }
    }

    /// Add every ghost's value to its owner's and zero the ghosts (`bs` values per local
    /// index). The owner adds what it receives process by process in rank order, each
    /// process's ghosts in their order, so the sums are the same on every run. Collective.
    pub fn reverse_add(&self, x: &mut [f64], bs: usize) {
        self.reverse_with(x, bs, |owner, ghost| *owner += ghost);
        let n = self.n_owned();
        x[n * bs..].iter_mut().for_each(|v| *v = 0.0);
    }

    /// Combine every ghost's value into its owner's with `op(owner, ghost)` (`bs` values per
    /// local index), in rank order as [`IndexMap::reverse_add`]; the ghosts keep their values
    /// (a forward scatter after it gives them the owners'). For reductions other than a sum:
    /// the smallest gap of a node, the largest status. Collective.
    pub fn reverse_with(&self, x: &mut [f64], bs: usize, op: impl Fn(&mut f64, f64)) {
        debug_assert_eq!(x.len(), self.n_local() * bs);
        let n = self.n_owned();
        let out: Vec<Vec<f64>> = self.recv.iter().map(|ks| ks.iter().flat_map(|&k| x[(n + k) * bs..(n + k + 1) * bs].iter().copied()).collect()).collect();
        let got = self.comm.exchange(&out);
        for (is, vals) in self.send.iter().zip(&got) {
            for (j, &i) in is.iter().enumerate() {
                for c in 0..bs {
                    op(&mut x[i * bs + c], vals[j * bs + c]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comm::Serial;

    #[test]
    fn one_process_owns_everything_and_scatters_nothing() {
        let m = IndexMap::new(Arc::new(Serial), 5, Vec::new()).unwrap();
        assert_eq!((m.n_owned(), m.n_local(), m.n_global(), m.start()), (5, 5, 5, 0));
        assert_eq!(m.global(3), 3);
        let mut x: Vec<f64> = (0..10).map(f64::from).collect();
        m.forward(&mut x, 2);
        m.reverse_add(&mut x, 2);
        assert_eq!(x, (0..10).map(f64::from).collect::<Vec<_>>());
    }

    #[test]
    fn bad_ghost_lists_are_refused_by_name() {
        let e = |g: Vec<usize>| IndexMap::new(Arc::new(Serial), 4, g).err();
        assert_eq!(e(vec![7]), Some(IndexMapError::OutOfRange { ghost: 7, n_global: 4 }));
        assert_eq!(e(vec![2]), Some(IndexMapError::OwnGhost { ghost: 2, rank: 0 }));
    }
}
