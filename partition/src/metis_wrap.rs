//! METIS 5: multilevel k-way partitioning ([`try_metis_kway`], [`metis_kway`]) and
//! nested-dissection fill-reducing ordering ([`metis_nd`]).
//!
//! METIS is C code built from the sources bundled with the `metis-sys` crate. Its random number
//! generator and signal-based error handling are process-global, so every call into METIS is
//! serialised by one lock: concurrent callers wait, and results are deterministic (METIS seeds
//! its generator at every call).
//!
//! Inputs are checked here before METIS sees them (METIS prints and aborts the call on malformed
//! input, or misbehaves on asymmetric graphs): a malformed graph, zero parts or sizes beyond
//! METIS's 32-bit indices are returned as [`PartitionError`], never a panic.

use crate::{greedy_bfs, Graph};
use metis::option::{Contig, NCuts, Opt};
use metis::Idx;
use std::fmt;
use std::sync::Mutex;

/// Serialises all calls into the METIS C library (global RNG state, signal handlers).
static METIS_LOCK: Mutex<()> = Mutex::new(());

/// Number of k-way partitions METIS computes (from different random seeds) to keep the one
/// with the smallest cut. On regular grids, where the coarsening has many ties, one try leaves
/// cuts up to 30 % above the best of 8 (32 × 32 grid, 4 parts: 81 vs 73 edges); the particle
/// graphs are small (one vertex per particle), so 8 tries cost milliseconds.
const KWAY_NCUTS: Idx = 8;

/// Why a METIS partition or ordering could not be computed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PartitionError {
    /// `nparts` was 0.
    NoParts,
    /// The graph violates the [`Graph`] invariants (message says which).
    InvalidGraph(String),
    /// Too many vertices, edges or too much total vertex weight for METIS's 32-bit indices.
    TooLarge(String),
    /// METIS itself reported an error.
    Metis(String),
}

impl fmt::Display for PartitionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PartitionError::NoParts => write!(f, "the number of parts must be at least 1"),
            PartitionError::InvalidGraph(m) => write!(f, "invalid graph: {m}"),
            PartitionError::TooLarge(m) => {
                write!(f, "graph too large for METIS (32-bit indices): {m}")
            }
            PartitionError::Metis(m) => write!(f, "METIS failed: {m}"),
        }
    }
}

impl std::error::Error for PartitionError {}

/// Checks the [`Graph`] invariants: `xadj` has `n + 1` non-decreasing entries from 0 to
/// `adjncy.len()`, neighbours are in `0..n`, no self loops, no repeated neighbours, and every
/// edge is stored in both directions.
pub fn validate(graph: &Graph) -> Result<(), PartitionError> {
    let n = graph.vwgt.len();
    let bad = |m: String| Err(PartitionError::InvalidGraph(m));
    if graph.xadj.len() != n + 1 {
        return bad(format!(
            "xadj has {} entries for {n} vertices (expected {})",
            graph.xadj.len(),
            n + 1
        ));
    }
    if graph.xadj[0] != 0 {
        return bad(format!("xadj[0] = {} (expected 0)", graph.xadj[0]));
    }
    if let Some(v) = (0..n).find(|&v| graph.xadj[v + 1] < graph.xadj[v]) {
        return bad(format!("xadj decreases at vertex {v}"));
    }
    if graph.xadj[n] != graph.adjncy.len() {
        return bad(format!(
            "xadj[n] = {} but adjncy has {} entries",
            graph.xadj[n],
            graph.adjncy.len()
        ));
    }
    // Per vertex: range, self loops and repeats (marker array, O(edges)).
    let mut mark = vec![usize::MAX; n];
    for v in 0..n {
        for &w in graph.neighbors(v) {
            if w >= n {
                return bad(format!("vertex {v} has neighbour {w} outside 0..{n}"));
            }
            if w == v {
                return bad(format!("vertex {v} has a self loop"));
            }
            if mark[w] == v {
                return bad(format!("vertex {v} lists neighbour {w} twice"));
            }
            mark[w] = v;
        }
    }
    // Symmetry: build the transpose (for every stored (v, w), entry v in row w) and check that
    // every row of the transpose holds the same neighbours as the graph's row. Rows have no
    // repeats, so equal lengths plus inclusion mean equal sets. O(edges).
    let mut tstart = vec![0usize; n + 1];
    for &w in &graph.adjncy {
        tstart[w + 1] += 1;
    }
    for v in 0..n {
        tstart[v + 1] += tstart[v];
    }
    let mut tadj = vec![0usize; graph.adjncy.len()];
    let mut next = tstart[..n].to_vec();
    for v in 0..n {
        for &w in graph.neighbors(v) {
            tadj[next[w]] = v;
            next[w] += 1;
        }
    }
    mark.fill(usize::MAX);
    for w in 0..n {
        for &x in graph.neighbors(w) {
            mark[x] = w;
        }
        let t = &tadj[tstart[w]..tstart[w + 1]];
        if t.len() != graph.neighbors(w).len() {
            return bad(format!("adjacency is not symmetric at vertex {w}"));
        }
        if let Some(&v) = t.iter().find(|&&v| mark[v] != w) {
            return bad(format!("edge ({v}, {w}) is stored in one direction only"));
        }
    }
    Ok(())
}

fn to_idx(x: usize, what: &str) -> Result<Idx, PartitionError> {
    Idx::try_from(x).map_err(|_| PartitionError::TooLarge(format!("{what} = {x}")))
}

fn idx_vec(v: &[usize], what: &str) -> Result<Vec<Idx>, PartitionError> {
    v.iter().map(|&x| to_idx(x, what)).collect()
}

/// Whether every vertex can be reached from vertex 0 (true for the empty graph).
pub fn is_connected(graph: &Graph) -> bool {
    let n = graph.n_vertices();
    if n == 0 {
        return true;
    }
    let mut seen = vec![false; n];
    let mut stack = vec![0];
    seen[0] = true;
    let mut count = 1;
    while let Some(v) = stack.pop() {
        for &w in graph.neighbors(v) {
            if !seen[w] {
                seen[w] = true;
                count += 1;
                stack.push(w);
            }
        }
    }
    count == n
}

/// METIS multilevel k-way partition (`METIS_PartGraphKway`, minimising the edge cut; the best
/// of 8 tries) that balances the vertex weights `graph.vwgt`: METIS's default tolerance lets
/// the heaviest part carry up to 3 % more than the average (a bound METIS can miss by a little
/// on small graphs with very uneven weights). Parts are contiguous when the graph is connected
/// (METIS's contiguity option, which it rejects on disconnected graphs, so it is only set for
/// connected ones). Deterministic.
///
/// Cases METIS rejects or handles poorly are answered directly: `nparts == 1` puts every vertex
/// in part 0, `nparts >= n` puts vertex `i` in part `i` (parts `n..nparts` stay empty), and the
/// empty graph gives an empty vector. A graph whose weights are all zero is balanced by vertex
/// count.
///
/// # Errors
/// `nparts == 0`, a malformed graph ([`validate`]), sizes or total weight beyond 32-bit
/// indices, or an error reported by METIS.
pub fn try_metis_kway(graph: &Graph, nparts: usize) -> Result<Vec<usize>, PartitionError> {
    if nparts == 0 {
        return Err(PartitionError::NoParts);
    }
    validate(graph)?;
    let n = graph.n_vertices();
    if nparts == 1 || n == 0 {
        return Ok(vec![0; n]);
    }
    if nparts >= n {
        return Ok((0..n).collect());
    }
    let xadj = idx_vec(&graph.xadj, "xadj entry")?;
    let adjncy = idx_vec(&graph.adjncy, "vertex index")?;
    let total: u64 = graph.total_weight();
    let vwgt: Vec<Idx> = if total == 0 {
        vec![1; n]
    } else {
        if total > Idx::MAX as u64 {
            return Err(PartitionError::TooLarge(format!(
                "total vertex weight = {total}"
            )));
        }
        graph.vwgt.iter().map(|&w| w as Idx).collect()
    };
    let np = to_idx(nparts, "nparts")?;
    let contig = is_connected(graph);
    let mut part: Vec<Idx> = vec![0; n];
    let cut = {
        let _guard = METIS_LOCK.lock().unwrap_or_else(|p| p.into_inner());
        let mut options = [-1; metis::NOPTIONS];
        options[Contig::INDEX] = Contig(contig).value();
        options[NCuts::INDEX] = NCuts(KWAY_NCUTS).value();
        metis::Graph::new(1, np, &xadj, &adjncy)
            .map_err(|e| PartitionError::InvalidGraph(e.to_string()))?
            .set_vwgt(&vwgt)
            .set_options(&options)
            .part_kway(&mut part)
            .map_err(|e| PartitionError::Metis(e.to_string()))?
    };
    let mut out = Vec::with_capacity(n);
    for (v, &p) in part.iter().enumerate() {
        match usize::try_from(p) {
            Ok(p) if p < nparts => out.push(p),
            _ => {
                return Err(PartitionError::Metis(format!(
                    "vertex {v} was given part {p} outside 0..{nparts}"
                )))
            }
        }
    }
    tracing::debug!(
        n,
        nparts,
        edge_cut = cut,
        contiguous = contig,
        "METIS k-way partition"
    );
    Ok(out)
}

/// [`try_metis_kway`] as a [`Partitioner`](crate::Partitioner): when METIS cannot partition the
/// graph (see the errors there) it logs a warning and returns [`greedy_bfs`]'s partition.
///
/// # Panics
/// If `nparts == 0`, or the graph is malformed (as [`greedy_bfs`]); use [`try_metis_kway`] to
/// get these as errors.
pub fn metis_kway(graph: &Graph, nparts: usize) -> Vec<usize> {
    match try_metis_kway(graph, nparts) {
        Ok(p) => p,
        Err(e) => {
            tracing::warn!("METIS k-way partition failed ({e}); using the greedy BFS partitioner");
            greedy_bfs(graph, nparts)
        }
    }
}

/// METIS nested-dissection fill-reducing ordering (`METIS_NodeND`, default options: vertices
/// with identical adjacency are compressed first, so the two displacement dofs of a node are
/// ordered together).
///
/// Returns `(perm, iperm)`: `perm[k]` is the original vertex eliminated `k`-th (row `k` of the
/// permuted matrix is row `perm[k]` of the original), `iperm` is its inverse
/// (`iperm[perm[k]] == k`). Vertex weights are ignored. Graphs of 0 or 1 vertices get the
/// identity without calling METIS.
///
/// # Errors
/// A malformed graph ([`validate`]), sizes beyond 32-bit indices, or an error reported by
/// METIS (including a result that is not a permutation).
pub fn metis_nd(graph: &Graph) -> Result<(Vec<usize>, Vec<usize>), PartitionError> {
    validate(graph)?;
    let n = graph.n_vertices();
    if n <= 1 {
        return Ok(((0..n).collect(), (0..n).collect()));
    }
    let mut nv = to_idx(n, "number of vertices")?;
    let mut xadj = idx_vec(&graph.xadj, "xadj entry")?;
    let mut adjncy = idx_vec(&graph.adjncy, "vertex index")?;
    let mut options: [Idx; metis::NOPTIONS] = [-1; metis::NOPTIONS];
    let mut perm: Vec<Idx> = vec![0; n];
    let mut iperm: Vec<Idx> = vec![0; n];
    let status = {
        let _guard = METIS_LOCK.lock().unwrap_or_else(|p| p.into_inner());
        // SAFETY: every array has the length METIS_NodeND reads or writes (n + 1, xadj[n], n,
        // n; `options` has METIS_NOPTIONS entries), the graph was validated (symmetric, in
        // range, no self loops), indices fit `idx_t`, and a null `vwgt` means unit weights.
        // METIS only writes `perm` and `iperm` and restores `xadj`/`adjncy` (we own copies).
        unsafe {
            metis_sys::METIS_NodeND(
                &mut nv,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                perm.as_mut_ptr(),
                iperm.as_mut_ptr(),
            )
        }
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        let what = match status {
            metis_sys::rstatus_et_METIS_ERROR_INPUT => "invalid input",
            metis_sys::rstatus_et_METIS_ERROR_MEMORY => "out of memory",
            _ => "error",
        };
        return Err(PartitionError::Metis(format!(
            "METIS_NodeND: {what} (status {status})"
        )));
    }
    // Check the answer is a permutation pair before handing it on.
    let mut p = Vec::with_capacity(n);
    let mut ip = vec![usize::MAX; n];
    for (k, &v) in perm.iter().enumerate() {
        match usize::try_from(v) {
            Ok(v) if v < n && ip[v] == usize::MAX => {
                ip[v] = k;
                p.push(v);
            }
            _ => {
                return Err(PartitionError::Metis(format!(
                    "METIS_NodeND: perm[{k}] = {v} is not a permutation"
                )))
            }
        }
    }
    if iperm
        .iter()
        .enumerate()
        .any(|(v, &k)| usize::try_from(k).ok() != Some(ip[v]))
    {
        return Err(PartitionError::Metis(
            "METIS_NodeND: iperm is not the inverse of perm".into(),
        ));
    }
    Ok((p, ip))
}

/// Undirected graph of a symmetric sparse matrix pattern for an ordering: the vertices are the
/// rows, an edge joins `i` and `j` when entry `(i, j)` or `(j, i)` is stored; the diagonal is
/// dropped. `row_ptr` / `col_idx` are CSR (or CSC) arrays of an `n × n` matrix; the pattern need
/// not be symmetric (it is symmetrised) nor sorted.
///
/// # Errors
/// If `row_ptr` does not have `n + 1` non-decreasing entries ending at `col_idx.len()`, or a
/// column index is `>= n`.
pub fn graph_of_pattern(
    n: usize,
    row_ptr: &[usize],
    col_idx: &[usize],
) -> Result<Graph, PartitionError> {
    let bad = |m: String| Err(PartitionError::InvalidGraph(m));
    if row_ptr.len() != n + 1 || row_ptr[0] != 0 || row_ptr[n] != col_idx.len() {
        return bad(format!(
            "row_ptr must have {} entries from 0 to {}",
            n + 1,
            col_idx.len()
        ));
    }
    if (0..n).any(|i| row_ptr[i + 1] < row_ptr[i]) {
        return bad("row_ptr decreases".into());
    }
    if let Some(&j) = col_idx.iter().find(|&&j| j >= n) {
        return bad(format!("column index {j} outside 0..{n}"));
    }
    // Degree count of A + Aᵀ without the diagonal (with duplicates), then fill, then sort and
    // deduplicate each list in place.
    let mut deg = vec![0usize; n];
    for i in 0..n {
        for &j in &col_idx[row_ptr[i]..row_ptr[i + 1]] {
            if i != j {
                deg[i] += 1;
                deg[j] += 1;
            }
        }
    }
    let mut start = vec![0usize; n + 1];
    for i in 0..n {
        start[i + 1] = start[i] + deg[i];
    }
    let mut adj = vec![0usize; start[n]];
    let mut next = start[..n].to_vec();
    for i in 0..n {
        for &j in &col_idx[row_ptr[i]..row_ptr[i + 1]] {
            if i != j {
                adj[next[i]] = j;
                next[i] += 1;
                adj[next[j]] = i;
                next[j] += 1;
            }
        }
    }
    let mut xadj = Vec::with_capacity(n + 1);
    let mut adjncy = Vec::with_capacity(start[n] / 2 + n);
    xadj.push(0);
    for i in 0..n {
        let l = &mut adj[start[i]..start[i + 1]];
        l.sort_unstable();
        let mut last = usize::MAX;
        for &j in l.iter() {
            if j != last {
                adjncy.push(j);
                last = j;
            }
        }
        xadj.push(adjncy.len());
    }
    Ok(Graph {
        xadj,
        adjncy,
        vwgt: vec![1; n],
    })
}
