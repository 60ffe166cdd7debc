//! Unit tests of the 4-wide BVH: structure invariants, traversal against a scan of every node,
//! pruning against a scan of every box, degenerate box sets.

use super::*;

/// A small deterministic generator (xorshift) for test boxes and rays.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.next()
    }
}

fn random_boxes(rng: &mut Rng, n: usize) -> Vec<Aabb> {
    (0..n)
        .map(|_| {
            let c = Vec3A::new(rng.range(-50.0, 50.0), rng.range(-50.0, 50.0), rng.range(250.0, 350.0));
            let h = Vec3A::new(rng.range(0.01, 2.0), rng.range(0.01, 2.0), rng.range(0.01, 2.0));
            Aabb { lo: c - h, hi: c + h }
        })
        .collect()
}

/// Every slot once; every child box contains the boxes below it.
fn check_structure(bvh: &Bvh4, boxes: &[Aabb]) {
    let mut seen = vec![false; boxes.len()];
    for &p in bvh.slots() {
        assert!(!std::mem::replace(&mut seen[p as usize], true), "primitive {p} in two slots");
    }
    assert!(seen.iter().all(|&s| s), "a primitive is missing");
    let contains = |outer: &Aabb, inner: &Aabb| outer.lo.cmple(inner.lo).all() && outer.hi.cmpge(inner.hi).all();
    // Box of a subtree (recomputed from the primitives), checked against the parent's copy.
    fn subtree(bvh: &Bvh4, r: u32, slots: &mut Vec<usize>) {
        if r & LEAF != 0 {
            let first = (r & ((1 << 27) - 1)) as usize;
            slots.extend(first..first + (((r >> 27) & 0xF) + 1) as usize);
            return;
        }
        for &c in &bvh.nodes[r as usize].child {
            if c != EMPTY {
                subtree(bvh, c, slots);
            }
        }
    }
    let mut leaf_slots = Vec::new();
    if bvh.root != EMPTY {
        subtree(bvh, bvh.root, &mut leaf_slots);
    }
    leaf_slots.sort_unstable();
    assert_eq!(leaf_slots, (0..boxes.len()).collect::<Vec<_>>(), "leaves do not cover the slots exactly once");
    for node in &bvh.nodes {
        for i in 0..4 {
            let c = node.child[i];
            if c == EMPTY {
                continue;
            }
            let child_box = Aabb {
                lo: Vec3A::new(node.lo_x[i], node.lo_y[i], node.lo_z[i]),
                hi: Vec3A::new(node.hi_x[i], node.hi_y[i], node.hi_z[i]),
            };
            let mut below = Vec::new();
            subtree(bvh, c, &mut below);
            assert!((1..=LEAF_MAX).contains(&below.len()) || c & LEAF == 0, "leaf of {} primitives", below.len());
            for s in below {
                let b = boxes[bvh.slots()[s] as usize];
                assert!(contains(&child_box, &b), "child box {child_box:?} does not contain {b:?}");
            }
        }
    }
}

/// The leaves the fast traversal visits when nothing is pruned, sorted.
fn visited(bvh: &Bvh4, ray: &CullRay) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    bvh.traverse(ray, |first, count, t| {
        out.push((first, count));
        t
    });
    out.sort_unstable();
    out
}

#[test]
fn structure_and_traversal_match_the_scan_of_all_nodes() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    // 300,000 exceeds PARALLEL_MIN: subtrees built in parallel and spliced.
    const { assert!(300_000 > PARALLEL_MIN) };
    for n in [0usize, 1, 3, 4, 5, 17, 100, 5000, 40_000, 300_000] {
        let boxes = random_boxes(&mut rng, n);
        let bvh = Bvh4::build(&boxes);
        check_structure(&bvh, &boxes);
        for k in 0..300 {
            let o = Vec3A::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
            let target = Vec3A::new(rng.range(-60.0, 60.0), rng.range(-60.0, 60.0), rng.range(240.0, 360.0));
            let t_max = if k % 3 == 0 { rng.range(0.5, 1.2) } else { f32::INFINITY };
            let ray = CullRay::new(o, target - o, t_max);
            let mut slow = bvh.leaves_entered(&ray);
            slow.sort_unstable();
            assert_eq!(visited(&bvh, &ray), slow, "n = {n}, ray {k}");
        }
    }
}

#[test]
fn coincident_and_exponentially_spread_boxes_build_bounded_trees() {
    // All centroids equal: splits fall back to halving by position.
    let same = vec![Aabb { lo: Vec3A::splat(-1.0), hi: Vec3A::splat(1.0) }; 1000];
    let bvh = Bvh4::build(&same);
    check_structure(&bvh, &same);
    assert!(bvh.depth() <= 6, "depth {}", bvh.depth());
    let ray = CullRay::new(Vec3A::new(0.0, 0.0, -10.0), Vec3A::Z, f32::INFINITY);
    assert_eq!(visited(&bvh, &ray).iter().map(|l| l.1).sum::<usize>(), 1000);

    // Boxes at 6^i along x, sizes spanning 37 orders of magnitude.
    let spread: Vec<Aabb> = (0..48)
        .map(|i| {
            let x = 6f32.powi(i);
            Aabb { lo: Vec3A::new(x, -1.0, -1.0), hi: Vec3A::new(x * 1.1, 1.0, 1.0) }
        })
        .collect();
    let bvh = Bvh4::build(&spread);
    check_structure(&bvh, &spread);
    assert!(bvh.depth() <= SAH_MAX_DEPTH + 16, "depth {}", bvh.depth());
    let ray = CullRay::new(Vec3A::new(0.5, 0.0, 0.0), Vec3A::X, f32::INFINITY);
    let mut slow = bvh.leaves_entered(&ray);
    slow.sort_unstable();
    assert_eq!(visited(&bvh, &ray), slow);
    // A traversal with its own stack (as for a nested traversal) visits the same leaves.
    let mut heap = Vec::new();
    bvh.traverse_in(&mut vec![(0, 0.0); 3 * bvh.depth() + 1], &ray, |first, count, t| {
        heap.push((first, count));
        t
    });
    heap.sort_unstable();
    assert_eq!(heap, slow);
    assert_eq!(slow.iter().map(|l| l.1).sum::<usize>(), 48);
}

#[test]
fn nested_traversal_uses_its_own_stack() {
    // A traversal from inside a leaf callback (the per-thread stack is busy) must work and
    // must not disturb the outer one.
    let mut rng = Rng(7);
    let boxes = random_boxes(&mut rng, 3000);
    let bvh = Bvh4::build(&boxes);
    let ray = CullRay::new(Vec3A::ZERO, Vec3A::new(0.0, 0.0, 1.0), f32::INFINITY);
    let (mut outer, mut inner_runs) = (Vec::new(), 0);
    bvh.traverse(&ray, |first, count, t| {
        outer.push((first, count));
        assert_eq!(visited(&bvh, &ray), {
            let mut slow = bvh.leaves_entered(&ray);
            slow.sort_unstable();
            slow
        });
        inner_runs += 1;
        t
    });
    outer.sort_unstable();
    let mut slow = bvh.leaves_entered(&ray);
    slow.sort_unstable();
    assert_eq!(outer, slow);
    assert!(inner_runs > 0);
}

#[test]
fn pruning_keeps_the_nearest_box() {
    // Each primitive "hits" where the ray enters its box; the traversal, pruning with the
    // best hit so far, must find the same nearest entry as a scan of every box.
    let mut rng = Rng(42);
    let boxes = random_boxes(&mut rng, 20_000);
    let bvh = Bvh4::build(&boxes);
    let entry = |b: &Aabb, o: Vec3A, d: Vec3A| {
        let inv = d.recip();
        let (a, c) = ((b.lo - o) * inv, (b.hi - o) * inv);
        let (t0, t1) = (a.min(c).max_element().max(0.0), a.max(c).min_element());
        (t0 <= t1).then_some(t0)
    };
    for _ in 0..500 {
        let o = Vec3A::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), 0.0);
        let d = Vec3A::new(rng.range(-60.0, 60.0), rng.range(-60.0, 60.0), 300.0) - o;
        let brute = boxes.iter().filter_map(|b| entry(b, o, d)).fold(f32::INFINITY, f32::min);
        let mut best = f32::INFINITY;
        bvh.traverse(&CullRay::new(o, d, f32::INFINITY), |first, count, t| {
            for s in first..first + count {
                if let Some(e) = entry(&boxes[bvh.slots()[s] as usize], o, d) {
                    best = best.min(e);
                }
            }
            t.min(best)
        });
        assert_eq!(best, brute);
    }
}
