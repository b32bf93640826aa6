//! Integration tests of the contact broad phase (`contact::search`).
//!
//! The central property is the broad-phase contract: for every search distance the set
//! returned by `ContactSearch::pairs` CONTAINS the exact brute-force set (no missed pair, checked
//! exactly, no tolerance), and every extra pair is within `distance + ℓ_max` of its segment
//! (ℓ_max the largest segment length; the bound the contract promises for any box-based
//! broad phase — ours is in fact much tighter, see `extra_pairs_are_only_round_off`).
//! Hand-computed distances are compared to 1e-15 relative (a handful of flops each).

use mpfem::contact::barrier::point_edge_toi;
use mpfem::contact::search::{
    boundary_of, brute_force_pairs, for_each_swept_pair, point_segment_distance, ContactSearch,
    NearPairs,
};
use mpfem::contact::Segment;
use mpfem::mesh::shapes;
use mpfem::mesh::Mesh;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// A tiny seeded RNG (xorshift64*), so the tests are reproducible without the rand crate.

struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn int(&mut self, lo: usize, hi_inclusive: usize) -> usize {
        lo + (self.next_u64() % (hi_inclusive - lo + 1) as u64) as usize
    }
}

// ---------------------------------------------------------------------------------------------
// Scene helpers

struct Scene {
    coords: Vec<[f64; 2]>,
    segments: Vec<Segment>,
    slaves: Vec<(usize, usize)>,
    h: f64,
}

/// A random particle: disc, ellipse or convex polygon (an affinely stretched, rotated regular
/// polygon: affine maps keep strict convexity), of size about 1 mm around `c`.
fn random_particle(rng: &mut Rng, c: [f64; 2], h: f64) -> Mesh {
    match rng.int(0, 2) {
        0 => shapes::disc(c, rng.range(0.5, 1.3), h),
        1 => shapes::ellipse(
            c,
            [rng.range(0.6, 1.4), rng.range(0.4, 0.9)],
            rng.range(0.0, 180.0),
            h,
        ),
        _ => {
            let n = rng.int(3, 8);
            let (sx, sy) = (rng.range(0.6, 1.3), rng.range(0.6, 1.3));
            let rot = rng.range(0.0, 2.0 * PI);
            let (cr, sr) = (rot.cos(), rot.sin());
            let v: Vec<[f64; 2]> = (0..n)
                .map(|k| {
                    let t = 2.0 * PI * k as f64 / n as f64;
                    let (x, y) = (sx * t.cos(), sy * t.sin());
                    [c[0] + cr * x - sr * y, c[1] + sr * x + cr * y]
                })
                .collect();
            shapes::convex_polygon(&v, h).expect("stretched regular polygon is convex")
        }
    }
}

/// 10–30 particles at random centres in a square box sized so that neighbours overlap or leave
/// gaps of a fraction of a millimetre (mean spacing ≈ 2 mm for particles ≈ 2 mm across).
fn random_scene(rng: &mut Rng) -> Scene {
    let n = rng.int(10, 30);
    let h = rng.range(0.2, 0.4);
    let side = 2.0 * (n as f64).sqrt();
    let meshes: Vec<Mesh> = (0..n)
        .map(|_| {
            let c = [rng.range(0.0, side), rng.range(0.0, side)];
            random_particle(rng, c, h)
        })
        .collect();
    let mut offsets = Vec::with_capacity(n);
    let mut coords = Vec::new();
    for m in &meshes {
        offsets.push(coords.len());
        coords.extend_from_slice(&m.nodes);
    }
    let list: Vec<(&Mesh, usize)> = meshes.iter().zip(offsets.iter().copied()).collect();
    let (segments, slaves) = boundary_of(&list);
    Scene {
        coords,
        segments,
        slaves,
        h,
    }
}

fn max_segment_length(coords: &[[f64; 2]], segs: &[Segment]) -> f64 {
    segs.iter()
        .map(|s| {
            let (a, b) = (coords[s.nodes[0]], coords[s.nodes[1]]);
            (b[0] - a[0]).hypot(b[1] - a[1])
        })
        .fold(0.0, f64::max)
}

fn body_of(slaves: &[(usize, usize)], node: usize) -> usize {
    let k = slaves.binary_search_by_key(&node, |&(n, _)| n).unwrap();
    slaves[k].1
}

/// The contract for one query: sorted without duplicates, no same-body pair, contains the
/// brute-force set, extras within `distance + ℓ_max`. Returns (broad, exact) sizes.
fn check_contract(
    search: &ContactSearch,
    coords: &[[f64; 2]],
    segs: &[Segment],
    slaves: &[(usize, usize)],
    distance: f64,
    what: &str,
) -> (usize, usize) {
    let broad = search.pairs(coords, slaves, distance);
    let exact = brute_force_pairs(coords, segs, slaves, distance);
    assert!(
        broad.windows(2).all(|w| w[0] < w[1]),
        "{what}: broad pairs not strictly sorted"
    );
    assert!(exact.windows(2).all(|w| w[0] < w[1]));
    for &(n, s) in &broad {
        assert_ne!(body_of(slaves, n), segs[s].body, "{what}: same-body pair");
    }
    for p in &exact {
        assert!(
            broad.binary_search(p).is_ok(),
            "{what}: missed pair {p:?} at distance {distance}"
        );
    }
    let lmax = max_segment_length(coords, segs);
    for &(n, s) in &broad {
        let d = point_segment_distance(
            coords[n],
            coords[segs[s].nodes[0]],
            coords[segs[s].nodes[1]],
        );
        assert!(
            d <= distance + lmax,
            "{what}: extra pair ({n}, {s}) at {d} > {distance} + {lmax}"
        );
    }
    (broad.len(), exact.len())
}

/// A smooth random deformation (two sine modes of amplitude up to `amp`) plus a per-node jitter
/// of up to `0.1 amp`, so neighbouring segments move differently.
fn deform(rng: &mut Rng, coords: &[[f64; 2]], amp: f64) -> Vec<[f64; 2]> {
    let (a1, a2) = (rng.range(-amp, amp), rng.range(-amp, amp));
    let (k1, k2) = (rng.range(0.2, 1.5), rng.range(0.2, 1.5));
    let (f1, f2) = (rng.range(0.0, 6.3), rng.range(0.0, 6.3));
    coords
        .iter()
        .map(|p| {
            [
                p[0] + a1 * (k1 * p[1] + f1).sin() + 0.1 * amp * rng.range(-1.0, 1.0),
                p[1] + a2 * (k2 * p[0] + f2).sin() + 0.1 * amp * rng.range(-1.0, 1.0),
            ]
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Random configurations

/// Broad phase ⊇ brute force on 12 random scenes, distances 0, 0.1h, h, 3h, before and after
/// deformations (small ones that refit the tree, then a large one that triggers a rebuild),
/// and also for moved coordinates passed without `update` (the drift inflation).
#[test]
fn random_scenes_never_miss_a_pair() {
    let mut rng = Rng::new(2024);
    let mut total_exact = 0;
    let mut total_broad = 0;
    for scene_id in 0..12 {
        let sc = random_scene(&mut rng);
        let dists = [0.0, 0.1 * sc.h, sc.h, 3.0 * sc.h];
        let mut search = ContactSearch::new(sc.segments.clone());

        // Before any update: a temporary hierarchy.
        for &d in &dists {
            check_contract(
                &search,
                &sc.coords,
                &sc.segments,
                &sc.slaves,
                d,
                &format!("scene {scene_id} no update"),
            );
        }

        search.update(&sc.coords);
        let mut coords = sc.coords.clone();
        // Small (refit) then large (rebuild) deformations, amplitudes in units of h.
        for (step, amp) in [0.0, 0.3, 0.5, 1.0, 5.0, 0.2].into_iter().enumerate() {
            if amp > 0.0 {
                let moved = deform(&mut rng, &coords, amp * sc.h);
                // Stale boxes: moved coordinates without update must still be conservative.
                for &d in &dists {
                    check_contract(
                        &search,
                        &moved,
                        &sc.segments,
                        &sc.slaves,
                        d,
                        &format!("scene {scene_id} step {step} stale"),
                    );
                }
                coords = moved;
                search.update(&coords);
            }
            for &d in &dists {
                let (b, e) = check_contract(
                    &search,
                    &coords,
                    &sc.segments,
                    &sc.slaves,
                    d,
                    &format!("scene {scene_id} step {step}"),
                );
                total_broad += b;
                total_exact += e;
            }
        }
    }
    // The scenes must actually exercise contact: plenty of pairs within the distances.
    assert!(total_exact > 1000, "too few exact pairs: {total_exact}");
    assert!(total_broad >= total_exact);
}

/// The Verlet list answers exactly what a search after an update answers (the same pairs in
/// the same order: the barrier's terms, hence a run's results, do not change with it), and
/// answers from its list while the motion since it was made is small: on 12 random scenes,
/// sequences of motions of 0.002–0.02 h (a Newton iteration's line search near convergence)
/// with a jump of 2 h now and then (a new step), at d̂ = h/20 and at h.
#[test]
fn the_verlet_list_gives_the_searchs_pairs_and_reuses_them_while_little_moves() {
    let mut rng = Rng::new(31);
    let (mut builds, mut queries, mut pairs) = (0, 0, 0);
    for scene_id in 0..12 {
        let sc = random_scene(&mut rng);
        for d in [sc.h / 20.0, sc.h] {
            let mut search = ContactSearch::new(sc.segments.clone());
            let mut reference = ContactSearch::new(sc.segments.clone());
            let mut near = NearPairs::default();
            let mut coords = sc.coords.clone();
            for step in 0..30 {
                let amp = if step % 10 == 9 { 2.0 } else { rng.range(0.002, 0.02) };
                coords = deform(&mut rng, &coords, amp * sc.h);
                let got = search.pairs_near(&mut near, &coords, &sc.slaves, d);
                reference.update(&coords);
                let want = reference.pairs(&coords, &sc.slaves, d);
                assert_eq!(got, want, "scene {scene_id}, d = {d}, step {step}");
                pairs += got.len();
            }
            // other slaves or another distance make the list again, and answer as the search
            let half = &sc.slaves[..sc.slaves.len() / 2];
            let before = near.builds;
            let got = search.pairs_near(&mut near, &coords, half, d);
            assert_eq!(got, reference.pairs(&coords, half, d), "scene {scene_id}: half the slaves");
            let got = search.pairs_near(&mut near, &coords, half, 0.5 * d);
            assert_eq!(got, reference.pairs(&coords, half, 0.5 * d), "scene {scene_id}: half the distance");
            assert_eq!(near.builds, before + 2, "scene {scene_id}: new slaves or distance make the list again");
            builds += near.builds;
            queries += near.queries;
        }
    }
    assert!(pairs > 10_000, "too few pairs to tell: {pairs}");
    // three jumps of 2 h in each sequence must make it again; the small motions mostly not
    // (the margin is at least d, a quarter of a segment: half of it allows 0.125 h of motion)
    assert!(builds >= 24 * 5, "the list was made {builds} times in {queries} queries: a jump must make it again");
    assert!(builds * 3 <= queries, "the list was made {builds} times in {queries} queries: small motions should reuse it");
}

/// Ours is tighter than the contract: the exact filter leaves only pairs within the round-off
/// pad (1e-12 × (1 + |x| + d)), so on random scenes the broad and exact sets coincide except
/// for pairs whose distance is within 1e-9 of `d` (generous versus the ~1e-11 pad).
#[test]
fn extra_pairs_are_only_round_off() {
    let mut rng = Rng::new(7);
    for _ in 0..4 {
        let sc = random_scene(&mut rng);
        let mut search = ContactSearch::new(sc.segments.clone());
        search.update(&sc.coords);
        for d in [0.0, 0.1 * sc.h, sc.h, 3.0 * sc.h] {
            let broad = search.pairs(&sc.coords, &sc.slaves, d);
            let exact = brute_force_pairs(&sc.coords, &sc.segments, &sc.slaves, d);
            for &(n, s) in &broad {
                if exact.binary_search(&(n, s)).is_err() {
                    let seg = sc.segments[s];
                    let dist = point_segment_distance(
                        sc.coords[n],
                        sc.coords[seg.nodes[0]],
                        sc.coords[seg.nodes[1]],
                    );
                    assert!(dist <= d + 1e-9, "extra pair at {dist} for d = {d}");
                }
            }
        }
    }
}

/// Duplicated slave entries and unsorted input still give a sorted duplicate-free list equal to
/// the brute force (which itself sorts and deduplicates).
#[test]
fn duplicate_and_unsorted_slaves() {
    let mut rng = Rng::new(99);
    let sc = random_scene(&mut rng);
    let mut slaves = sc.slaves.clone();
    slaves.extend_from_slice(&sc.slaves[..sc.slaves.len() / 2]);
    slaves.reverse();
    let mut search = ContactSearch::new(sc.segments.clone());
    search.update(&sc.coords);
    let d = sc.h;
    let broad = search.pairs(&sc.coords, &slaves, d);
    assert!(broad.windows(2).all(|w| w[0] < w[1]));
    let exact = brute_force_pairs(&sc.coords, &sc.segments, &slaves, d);
    assert!(exact.iter().all(|p| broad.binary_search(p).is_ok()));
}

// ---------------------------------------------------------------------------------------------
// Exact cases

/// Two unit squares (2 × 2 elements) side by side with a gap of exactly 0.5 mm (x = 1 and
/// x = 1.5, both exact in binary). Pairs appear at d = 0.5 (the facing nodes project onto the
/// facing segments at exactly 0.5) and not below; d = 0.5 − 1e-9 is far outside the
/// round-off pad (~4e-12 here). For 0.5 ≤ d < √2/2 the pairs are exactly: each of the 3 facing
/// nodes with the 2 segments of the other square that touch the facing point at distance 0.5
/// (the middle node: the two facing segments; a corner node: the facing segment and the
/// top/bottom segment starting at the facing corner) — 2 sides × 3 nodes × 2 = 12 pairs, all at
/// distance exactly 0.5.
#[test]
fn two_squares_with_a_gap() {
    let a = shapes::rectangle([0.0, 0.0], 1.0, 1.0, 2, 2);
    let b = shapes::rectangle([1.5, 0.0], 1.0, 1.0, 2, 2);
    let off = a.n_nodes();
    let mut coords = a.nodes.clone();
    coords.extend_from_slice(&b.nodes);
    let (segs, slaves) = boundary_of(&[(&a, 0), (&b, off)]);
    assert_eq!(segs.len(), 16);
    assert_eq!(slaves.len(), 16);
    let mut search = ContactSearch::new(segs.clone());
    search.update(&coords);

    for d in [0.0, 0.25, 0.5 - 1e-9] {
        assert!(search.pairs(&coords, &slaves, d).is_empty(), "d = {d}");
        assert!(brute_force_pairs(&coords, &segs, &slaves, d).is_empty());
    }
    for d in [0.5, 0.6, 0.7] {
        // 0.7 < √2/2 ≈ 0.7071.
        let p = search.pairs(&coords, &slaves, d);
        assert_eq!(p, brute_force_pairs(&coords, &segs, &slaves, d), "d = {d}");
        assert_eq!(p.len(), 12, "d = {d}: {p:?}");
        for &(n, s) in &p {
            let x = coords[n][0];
            let seg = segs[s];
            let (xa, xb) = (coords[seg.nodes[0]][0], coords[seg.nodes[1]][0]);
            if seg.body == 1 {
                assert!(x == 1.0 && xa.min(xb) == 1.5);
            } else {
                assert!(x == 1.5 && xa.max(xb) == 1.0);
            }
            let dist =
                point_segment_distance(coords[n], coords[seg.nodes[0]], coords[seg.nodes[1]]);
            assert_eq!(dist, 0.5);
        }
    }
    // Beyond √2/2 the corner nodes also reach the other facing segment.
    assert!(search.pairs(&coords, &slaves, 0.75).len() > 12);
}

/// A node exactly on a segment (distance 0) is found, both ways: a small square sitting on top
/// of a unit square, its bottom corners (0.25, 1) and (0.75, 1) inside the unit square's top
/// segments, and the unit square's top mid node (0.5, 1) inside the small square's bottom
/// segment. Exactly these 3 pairs at d = 0 (all coordinates are exact binary fractions).
#[test]
fn node_exactly_on_a_segment() {
    let a = shapes::rectangle([0.0, 0.0], 1.0, 1.0, 2, 2);
    let b = shapes::rectangle([0.25, 1.0], 0.5, 0.5, 1, 1);
    let off = a.n_nodes();
    let mut coords = a.nodes.clone();
    coords.extend_from_slice(&b.nodes);
    let (segs, slaves) = boundary_of(&[(&a, 0), (&b, off)]);
    let mut search = ContactSearch::new(segs.clone());
    search.update(&coords);
    let p = search.pairs(&coords, &slaves, 0.0);
    assert_eq!(p, brute_force_pairs(&coords, &segs, &slaves, 0.0));
    assert_eq!(p.len(), 3, "{p:?}");
    let mut found: Vec<[f64; 2]> = p.iter().map(|&(n, _)| coords[n]).collect();
    found.sort_by(|x, y| x.partial_cmp(y).unwrap());
    assert_eq!(found, vec![[0.25, 1.0], [0.5, 1.0], [0.75, 1.0]]);
    for &(n, s) in &p {
        let sg = segs[s];
        assert_eq!(
            point_segment_distance(coords[n], coords[sg.nodes[0]], coords[sg.nodes[1]]),
            0.0
        );
    }
}

/// No pair within one body, even for a distance larger than the body: a lone disc gives
/// nothing, and two bodies give only cross-body pairs.
#[test]
fn no_pair_within_a_body() {
    let m = shapes::disc([0.0, 0.0], 1.0, 0.2);
    let (segs, slaves) = boundary_of(&[(&m, 0)]);
    let mut search = ContactSearch::new(segs.clone());
    search.update(&m.nodes);
    assert!(search.pairs(&m.nodes, &slaves, 10.0).is_empty());
    assert!(brute_force_pairs(&m.nodes, &segs, &slaves, 10.0).is_empty());

    let m2 = shapes::disc([1.9, 0.0], 1.0, 0.2);
    let mut coords = m.nodes.clone();
    coords.extend_from_slice(&m2.nodes);
    let (segs, slaves) = boundary_of(&[(&m, 0), (&m2, m.n_nodes())]);
    let mut search = ContactSearch::new(segs.clone());
    search.update(&coords);
    let p = search.pairs(&coords, &slaves, 10.0);
    // Every node of one disc with every segment of the other.
    let nb0 = slaves.iter().filter(|s| s.1 == 0).count();
    let nb1 = slaves.len() - nb0;
    let sb0 = segs.iter().filter(|s| s.body == 0).count();
    let sb1 = segs.len() - sb0;
    assert_eq!(p.len(), nb0 * sb1 + nb1 * sb0);
    for &(n, s) in &p {
        assert_ne!(body_of(&slaves, n), segs[s].body);
    }
}

/// Degenerate sizes (parry special-cases trees of 0, 1 and 2 leaves), a negative distance, and
/// a refit of a 1- and 2-leaf tree after a move.
#[test]
fn tiny_and_empty_inputs() {
    let coords = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 0.3], [3.0, 0.0], [3.0, 1.0]];
    let slaves = vec![(2, 9), (3, 1)];
    let mut s0 = ContactSearch::new(vec![]);
    s0.update(&coords);
    assert!(s0.pairs(&coords, &slaves, 5.0).is_empty());

    let seg_a = Segment {
        body: 0,
        nodes: [0, 1],
    };
    let seg_b = Segment {
        body: 1,
        nodes: [3, 4],
    };
    for segs in [vec![seg_a], vec![seg_a, seg_b]] {
        let mut s = ContactSearch::new(segs.clone());
        s.update(&coords);
        assert_eq!(s.pairs(&coords, &slaves, 0.3), vec![(2, 0)]);
        assert!(s.pairs(&coords, &slaves, 0.299).is_empty());
        assert!(s.pairs(&coords, &slaves, -1.0).is_empty());
        // Move segment 0 up by 0.2 (a refit: less than its length), node 2 now 0.1 away.
        let mut moved = coords.clone();
        moved[0][1] += 0.2;
        moved[1][1] += 0.2;
        s.update(&moved);
        assert_eq!(s.pairs(&moved, &slaves, 0.1 + 1e-9), vec![(2, 0)]);
        for d in [0.05, 0.1, 2.0, 3.0] {
            let b = s.pairs(&moved, &slaves, d);
            let e = brute_force_pairs(&moved, &segs, &slaves, d);
            assert!(e.iter().all(|p| b.contains(p)), "d = {d}");
        }
    }
}

/// `boundary_of` numbers the bodies in list order, shifts node indices by the offsets, keeps
/// the orientation and lists each boundary node once.
#[test]
fn boundary_of_layout() {
    let a = shapes::rectangle([0.0, 0.0], 1.0, 1.0, 3, 2);
    let b = shapes::disc([5.0, 0.0], 1.0, 0.3);
    let off = a.n_nodes() + 7; // offsets need not be contiguous
    let (segs, slaves) = boundary_of(&[(&a, 0), (&b, off)]);
    assert_eq!(segs.len(), a.boundary.len() + b.boundary.len());
    for (k, e) in a.boundary.iter().enumerate() {
        assert_eq!(segs[k], Segment { body: 0, nodes: *e });
    }
    for (k, e) in b.boundary.iter().enumerate() {
        assert_eq!(
            segs[a.boundary.len() + k],
            Segment {
                body: 1,
                nodes: [e[0] + off, e[1] + off]
            }
        );
    }
    assert!(slaves.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(slaves.len(), a.boundary.len() + b.boundary.len()); // closed loops
}

// ---------------------------------------------------------------------------------------------
// point_segment_distance

/// Hand values: interior projection, beyond each end, on the segment, an oblique segment and a
/// degenerate (zero-length) one. 3-4-5 triangles are exact; the others to 1e-15 relative.
#[test]
fn point_segment_distance_hand_values() {
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-15 * y.abs().max(1.0);
    let (a, b) = ([0.0, 0.0], [4.0, 0.0]);
    assert_eq!(point_segment_distance([1.0, 3.0], a, b), 3.0); // interior, above
    assert_eq!(point_segment_distance([2.5, -0.5], a, b), 0.5); // interior, below
    assert_eq!(point_segment_distance([-3.0, 4.0], a, b), 5.0); // beyond a
    assert_eq!(point_segment_distance([7.0, -4.0], a, b), 5.0); // beyond b
    assert_eq!(point_segment_distance([6.0, 0.0], a, b), 2.0); // on the line, beyond b
    assert_eq!(point_segment_distance([2.0, 0.0], a, b), 0.0); // on the segment
    assert_eq!(point_segment_distance([4.0, 0.0], a, b), 0.0); // at an end
    assert_eq!(point_segment_distance([-3.0, 4.0], b, a), 5.0); // orientation-free

    // Oblique segment (0,0)–(2,2): (2,0) projects on (1,1) at √2; (3,4) beyond b at √5.
    assert!(close(
        point_segment_distance([2.0, 0.0], [0.0, 0.0], [2.0, 2.0]),
        2f64.sqrt()
    ));
    assert!(close(
        point_segment_distance([3.0, 4.0], [0.0, 0.0], [2.0, 2.0]),
        5f64.sqrt()
    ));
    assert!(close(
        point_segment_distance([-1.0, -2.0], [0.0, 0.0], [2.0, 2.0]),
        5f64.sqrt()
    ));
    // Degenerate segment: the distance to the point.
    assert_eq!(
        point_segment_distance([4.0, 5.0], [1.0, 1.0], [1.0, 1.0]),
        5.0
    );
}

// ---------------------------------------------------------------------------------------------
// The swept broad phase of the continuous collision detection

/// Every pair of different bodies with a time of impact in [0, 1] (exact O(N·M) reference).
fn brute_force_impacts(x0: &[[f64; 2]], x1: &[[f64; 2]], segs: &[Segment], slaves: &[(usize, usize)]) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::new();
    for &(node, body) in slaves {
        for (s, seg) in segs.iter().enumerate() {
            if seg.body == body {
                continue;
            }
            let [a, b] = seg.nodes;
            if let Some(t) = point_edge_toi([x0[node], x0[a], x0[b]], [x1[node], x1[a], x1[b]]) {
                out.push((node, s, t));
            }
        }
    }
    out
}

/// `for_each_swept_pair` hands out every pair that meets during the motion (compared with the
/// time of impact of every pair of different bodies, exactly: same pairs, same first time of
/// impact), each once, never a pair within one body; on 12 random scenes under motions from
/// 0.3 h to 5 h, which make hundreds of impacts.
#[test]
fn swept_pairs_hold_every_impact() {
    let mut rng = Rng::new(77);
    let mut impacts = 0;
    for scene_id in 0..12 {
        let sc = random_scene(&mut rng);
        for amp in [0.3, 1.0, 5.0] {
            let x1 = deform(&mut rng, &sc.coords, amp * sc.h);
            let mut swept = Vec::new();
            for_each_swept_pair(&sc.segments, &sc.coords, &x1, &sc.slaves, |n, s| swept.push((n, s)));
            let count = swept.len();
            swept.sort_unstable();
            swept.dedup();
            assert_eq!(swept.len(), count, "scene {scene_id}: a pair handed out twice");
            for &(n, s) in &swept {
                assert_ne!(body_of(&sc.slaves, n), sc.segments[s].body, "scene {scene_id}: a pair within one body");
            }
            let exact = brute_force_impacts(&sc.coords, &x1, &sc.segments, &sc.slaves);
            for &(n, s, t) in &exact {
                assert!(swept.binary_search(&(n, s)).is_ok(), "scene {scene_id}, motion {amp} h: node {n} meets segment {s} at t = {t} but is not a swept pair");
            }
            impacts += exact.len();
        }
    }
    assert!(impacts > 200, "too few impacts to exercise the search: {impacts}");
}

/// The Verlet list answers the collision detection's broad phase for a small motion: where
/// `NearPairs::sweep_candidates` gives its list for a straight motion from x0 to x1, every
/// pair that meets on the way (exact times of impact of every pair of different bodies) is in
/// it. On 12 random scenes (overlapping particles: hundreds of
/// impacts), lists made at d̂ = h/20 and h, motions of 0.01–0.1 h from a configuration itself
/// 0–0.1 h from where the list was made; a translation by 2 (d̂ + h) gets no list, nor do
/// other slaves.
#[test]
fn the_verlet_list_holds_every_impact_of_a_small_motion() {
    let mut rng = Rng::new(4242);
    let (mut used, mut impacts) = (0, 0);
    for scene_id in 0..12 {
        let sc = random_scene(&mut rng);
        for d in [sc.h / 20.0, sc.h] {
            let mut search = ContactSearch::new(sc.segments.clone());
            let mut near = NearPairs::default();
            assert!(near.sweep_candidates(&sc.coords, &sc.coords, &sc.slaves).is_none(), "no list before one is made");
            search.pairs_near(&mut near, &sc.coords, &sc.slaves, d);
            for k in 0..30 {
                let (a0, a1) = (rng.range(0.0, 0.1), rng.range(0.01, 0.1));
                let x0 = deform(&mut rng, &sc.coords, a0 * sc.h);
                let x1 = deform(&mut rng, &x0, a1 * sc.h);
                let Some(list) = near.sweep_candidates(&x0, &x1, &sc.slaves) else { continue };
                used += 1;
                let mut list = list.to_vec();
                list.sort_unstable();
                for (n, s, t) in brute_force_impacts(&x0, &x1, &sc.segments, &sc.slaves) {
                    assert!(list.binary_search(&(n, s)).is_ok(), "scene {scene_id}, d = {d}, motion {k}: node {n} meets segment {s} at t = {t} but is not in the list");
                    impacts += 1;
                }
            }
            let far: Vec<[f64; 2]> = sc.coords.iter().map(|p| [p[0] + 2.0 * (d + sc.h), p[1]]).collect();
            assert!(near.sweep_candidates(&sc.coords, &far, &sc.slaves).is_none(), "scene {scene_id}: a jump of 2 (d + h) needs a search");
            assert!(near.sweep_candidates(&sc.coords, &sc.coords, &sc.slaves[1..]).is_none(), "scene {scene_id}: other slaves need a search");
        }
    }
    assert!(used >= 300, "the list answered only {used} motions");
    assert!(impacts > 200, "too few impacts to tell: {impacts} in {used} motions");
}

/// One particle sent 20 mm across the others (a soft mode's Newton update) while the rest stay:
/// the pairs of two resting particles are only those where the node lies in the segment's box
/// (so within the segment's length of it), not every pair within the largest motion as a
/// search of that radius gives.
#[test]
fn one_far_motion_does_not_make_every_pair_a_candidate() {
    let mut rng = Rng::new(5);
    let sc = random_scene(&mut rng);
    let moving = sc.slaves[0].1;
    let x1: Vec<[f64; 2]> = sc
        .coords
        .iter()
        .enumerate()
        .map(|(n, p)| match sc.slaves.binary_search_by_key(&n, |&(m, _)| m) {
            Ok(k) if sc.slaves[k].1 == moving => [p[0] + 20.0, p[1] + 7.0],
            _ => *p,
        })
        .collect();
    let mut resting = 0;
    let mut with_moving = 0;
    for_each_swept_pair(&sc.segments, &sc.coords, &x1, &sc.slaves, |n, s| {
        let seg = sc.segments[s];
        if body_of(&sc.slaves, n) == moving || seg.body == moving {
            with_moving += 1;
        } else {
            resting += 1;
            let (a, b) = (sc.coords[seg.nodes[0]], sc.coords[seg.nodes[1]]);
            let d = point_segment_distance(sc.coords[n], a, b);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            assert!(d <= len + 1e-6, "resting node {n} and segment {s} are {d} mm apart, more than the segment's length {len}");
        }
    });
    assert!(with_moving > 0, "the moving particle sweeps past nothing");
    // a search within the largest motion (21 mm) takes every pair of the scene
    let everything = search_radius_pairs(&sc, 2.0 * 21.1);
    assert!(resting + with_moving < everything / 4, "{resting} + {with_moving} swept pairs against {everything} within the motion");
}

fn search_radius_pairs(sc: &Scene, r: f64) -> usize {
    brute_force_pairs(&sc.coords, &sc.segments, &sc.slaves, r).len()
}
