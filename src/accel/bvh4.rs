//! [`Bvh4`]: inimtrace's own 4-wide bounding-volume hierarchy over `f32` boxes, the tree behind
//! the pure-Rust mesh backend ([`crate::accel::bvh::BvhIntersector`]; paper Sec. 3.1, "each ray
//! is traversed until it hits an object"). It only *culls*: it knows boxes and primitive slots,
//! never triangles, and the caller decides hits in its leaf callback.
//!
//! * **Build**: top-down binned surface-area heuristic (16 bins on each axis, all three axes
//!   binned in one pass), two binary splits per node giving up to four children, leaves of at most
//!   [`LEAF_MAX`] primitives. Subtrees over [`PARALLEL_MIN`] primitives are built in parallel
//!   (`rayon::join`) into their own node arrays and spliced together. Past [`SAH_MAX_DEPTH`] levels
//!   the splits fall back to centroid medians, which bounds the depth (and the traversal stack).
//! * **Traversal**: one ray at a time, the four child boxes of a node tested at once with glam's
//!   `Vec4` (SSE on x86-64), nearest child first, the others pushed with their entry distance so
//!   that they are skipped once a closer hit is known.
//!
//! docs/BVH.md has the measurements against the `obvhs` crate and Embree.

use glam::{Vec3A, Vec4};

/// Most primitives in one leaf.
pub const LEAF_MAX: usize = 4;
/// Subtrees with at least this many primitives are built in parallel.
pub const PARALLEL_MIN: usize = 131_072;
/// Levels of SAH splits before median splits take over (see [`Bvh4::depth`]).
pub const SAH_MAX_DEPTH: usize = 40;
/// SAH bins per axis (a power of two, see [`BIN_MASK`]).
const BINS: usize = 16;
const BIN_MASK: u32 = BINS as u32 - 1;
/// 2^23: adding it to a float in `[0, 2^22)` leaves the rounded integer in the mantissa's low bits.
const MAGIC: f32 = 8_388_608.0;
/// Nodes with at least this many primitives are binned on all three axes, smaller ones only on
/// the axis of widest centroid spread.
const ALL_AXES_MIN: usize = 2048;
/// Nodes with at least this many primitives are binned in parallel.
const PARALLEL_BINNING_MIN: usize = 262_144;
/// Largest primitive count a leaf reference can hold (27 bits of slot index).
pub const MAX_PRIMITIVES: usize = 1 << 27;

/// Set in an [`Item`]'s index bits (see there).
const ID_TAG: u32 = 0x4000_0000;

thread_local! {
    /// Per-thread traversal stack of [`Bvh4::traverse`] (grown to the deepest tree seen).
    static STACK: std::cell::RefCell<Vec<(u32, f32)>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Child reference: an interior node's index, a leaf (`LEAF` bit, count - 1 in bits 27..=30,
/// first slot in bits 0..=26), or [`EMPTY`].
const LEAF: u32 = 1 << 31;
const EMPTY: u32 = u32::MAX;

fn leaf_ref(first: usize, count: usize) -> u32 {
    debug_assert!((1..=16).contains(&count) && first < MAX_PRIMITIVES);
    LEAF | (((count - 1) as u32) << 27) | first as u32
}

/// An axis-aligned box in `f32`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub lo: Vec3A,
    /// Upper corner.
    pub hi: Vec3A,
}

impl Aabb {
    /// The empty box (grows to anything).
    pub const EMPTY: Aabb = Aabb { lo: Vec3A::splat(f32::INFINITY), hi: Vec3A::splat(f32::NEG_INFINITY) };
}

/// Four child boxes in structure-of-arrays form, and the four child references: 112 bytes,
/// aligned to the 64-byte cache line so that a node spans exactly two lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node {
    lo_x: Vec4,
    lo_y: Vec4,
    lo_z: Vec4,
    hi_x: Vec4,
    hi_y: Vec4,
    hi_z: Vec4,
    child: [u32; 4],
}

impl Node {
    const EMPTY: Node = Node {
        lo_x: Vec4::INFINITY,
        lo_y: Vec4::INFINITY,
        lo_z: Vec4::INFINITY,
        hi_x: Vec4::NEG_INFINITY,
        hi_y: Vec4::NEG_INFINITY,
        hi_z: Vec4::NEG_INFINITY,
        child: [EMPTY; 4],
    };

    fn set(&mut self, i: usize, b: &Aabb, child: u32) {
        self.lo_x[i] = b.lo.x;
        self.lo_y[i] = b.lo.y;
        self.lo_z[i] = b.lo.z;
        self.hi_x[i] = b.hi.x;
        self.hi_y[i] = b.hi.y;
        self.hi_z[i] = b.hi.z;
        self.child[i] = child;
    }
}

/// A ray prepared for [`Bvh4::traverse`]: `origin + t dir` for `0 <= t <= t_max`, in `f32`.
#[derive(Clone, Copy, Debug)]
pub struct CullRay {
    ox: Vec4,
    oy: Vec4,
    oz: Vec4,
    ix: Vec4,
    iy: Vec4,
    iz: Vec4,
    /// The ray's far limit (its parameter `t`), shrunk to the nearest hit found so far.
    pub t_max: f32,
}

impl CullRay {
    /// `dir` need not be normalised; `t` is in its units. A zero (or subnormal) component gets
    /// an infinite inverse: the slab bounds are then `+-inf` (the ray never leaves or never
    /// enters that slab), or NaN when the origin lies exactly on a face plane, which culls the
    /// box or ignores that axis. Either is safe for boxes padded around their primitives, as the
    /// mesh backend's are: a ray inside a face plane cannot reach a primitive strictly inside.
    pub fn new(origin: Vec3A, dir: Vec3A, t_max: f32) -> CullRay {
        let inv = dir.recip();
        CullRay {
            ox: Vec4::splat(origin.x),
            oy: Vec4::splat(origin.y),
            oz: Vec4::splat(origin.z),
            ix: Vec4::splat(inv.x),
            iy: Vec4::splat(inv.y),
            iz: Vec4::splat(inv.z),
            t_max,
        }
    }
}

/// The 4-wide tree. Leaves refer to *slots* `0..n`; [`Bvh4::slots`] maps each slot to the index
/// of the primitive (in the caller's order) that it holds.
#[derive(Clone, Debug)]
pub struct Bvh4 {
    nodes: Vec<Node>,
    /// Reference to the root: an interior node (index 0), a single leaf, or EMPTY.
    root: u32,
    slots: Vec<u32>,
    depth: usize,
}

/// A primitive's box during the build, with its index in the `w` lane of `lo`: the index's bits
/// with [`ID_TAG`] set, which makes the lane a normal float (exponent 128..=143), so that the
/// arithmetic done on whole `Vec4`s never meets a subnormal (x86 slows down ~100x on those).
/// Moving these 32-byte records instead of indices keeps every build pass sequential in memory.
#[derive(Clone, Copy, Debug)]
struct Item {
    lo: Vec4,
    hi: Vec4,
}

impl Item {
    #[inline]
    fn id(&self) -> u32 {
        self.lo.w.to_bits() & (MAX_PRIMITIVES as u32 - 1)
    }

    /// Twice the centroid (the binning only needs positions up to a common scale).
    #[inline]
    fn center2(&self) -> Vec4 {
        (self.lo + self.hi) * Vec4::new(1.0, 1.0, 1.0, 0.0)
    }
}

/// A box being grown during the build (`w` lanes ignored).
#[derive(Clone, Copy, Debug)]
struct Box4 {
    lo: Vec4,
    hi: Vec4,
}

impl Box4 {
    const EMPTY: Box4 = Box4 { lo: Vec4::INFINITY, hi: Vec4::NEG_INFINITY };

    #[inline]
    fn grow(&mut self, item: &Item) {
        self.lo = self.lo.min(item.lo);
        self.hi = self.hi.max(item.hi);
    }

    #[inline]
    fn grow_box(&mut self, b: &Box4) {
        self.lo = self.lo.min(b.lo);
        self.hi = self.hi.max(b.hi);
    }

    #[inline]
    fn grow_point(&mut self, p: Vec4) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    #[inline]
    fn half_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec4::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    fn aabb(&self) -> Aabb {
        Aabb { lo: Vec3A::from_vec4(self.lo), hi: Vec3A::from_vec4(self.hi) }
    }
}

impl Bvh4 {
    /// Builds the tree over `boxes` (primitive `i` has box `boxes[i]`). Boxes must be finite and
    /// non-inverted; the caller validates its primitives first.
    ///
    /// # Panics
    /// If there are more than [`MAX_PRIMITIVES`] boxes.
    pub fn build(boxes: &[Aabb]) -> Bvh4 {
        Bvh4::build_with(boxes.len(), |i| boxes[i])
    }

    /// As [`Bvh4::build`], with primitive `i`'s box given by `box_of(i)` for `i < n` (called
    /// once per primitive, in parallel), so that large scenes need no intermediate box array.
    ///
    /// # Panics
    /// If `n` exceeds [`MAX_PRIMITIVES`].
    pub fn build_with(n: usize, box_of: impl Fn(usize) -> Aabb + Sync) -> Bvh4 {
        use rayon::prelude::*;
        assert!(n <= MAX_PRIMITIVES, "Bvh4: {n} primitives, at most {MAX_PRIMITIVES}");
        if n == 0 {
            return Bvh4 { nodes: Vec::new(), root: EMPTY, slots: Vec::new(), depth: 0 };
        }
        let mut items: Vec<Item> = (0..n)
            .into_par_iter()
            .map(|i| {
                let b = box_of(i);
                Item { lo: b.lo.extend(f32::from_bits(i as u32 | ID_TAG)), hi: b.hi.extend(0.0) }
            })
            .collect();
        let (nodes, root, depth) = if n <= LEAF_MAX {
            (Vec::new(), leaf_ref(0, n), 0)
        } else {
            let (_, cbounds) = range_bounds(&items);
            let (mut nodes, depth) = build_subtree(&mut items, 0, cbounds, 1);
            // The root is at index 0 of its own array; nothing to relocate.
            nodes.shrink_to_fit();
            (nodes, 0, depth)
        };
        let slots = items.par_iter().map(Item::id).collect();
        Bvh4 { nodes, root, slots, depth }
    }

    /// Slot `s` of every leaf holds primitive `slots()[s]`.
    pub fn slots(&self) -> &[u32] {
        &self.slots
    }

    /// Levels of interior nodes on the longest root-to-leaf path.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Number of interior nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Visits, nearest box first, every leaf whose box the ray enters within `[0, ray.t_max]`,
    /// calling `leaf(first_slot, count, t_max)`. The callback returns the new `t_max` (at most the
    /// one passed: boxes entered beyond it are skipped from then on); a negative value ends the
    /// traversal (any-hit queries).
    #[inline]
    pub fn traverse(&self, ray: &CullRay, leaf: impl FnMut(usize, usize, f32) -> f32) {
        // At most 3 entries per level are pending. The stack lives in a per-thread buffer, so a
        // ray does not pay for setting one up; a traversal started from inside a leaf callback
        // (the buffer is then in use) gets a fresh one.
        let need = 3 * self.depth + 1;
        STACK.with(|buffer| match buffer.try_borrow_mut() {
            Ok(mut stack) => {
                if stack.len() < need {
                    stack.resize(need, (0, 0.0));
                }
                self.traverse_in(&mut stack[..need], ray, leaf)
            }
            Err(_) => self.traverse_in(&mut vec![(0, 0.0); need], ray, leaf),
        })
    }

    #[inline]
    fn traverse_in(&self, stack: &mut [(u32, f32)], ray: &CullRay, mut leaf: impl FnMut(usize, usize, f32) -> f32) {
        let mut t_max = ray.t_max;
        if self.root == EMPTY || t_max.is_nan() || t_max < 0.0 {
            return;
        }
        let mut sp = 0usize;
        let mut current = self.root;
        loop {
            if current & LEAF == 0 {
                let node = &self.nodes[current as usize];
                // Slab test of the four children at once.
                let x0 = (node.lo_x - ray.ox) * ray.ix;
                let x1 = (node.hi_x - ray.ox) * ray.ix;
                let y0 = (node.lo_y - ray.oy) * ray.iy;
                let y1 = (node.hi_y - ray.oy) * ray.iy;
                let z0 = (node.lo_z - ray.oz) * ray.iz;
                let z1 = (node.hi_z - ray.oz) * ray.iz;
                let near = x0.min(x1).max(y0.min(y1)).max(z0.min(z1)).max(Vec4::ZERO);
                let far = x0.max(x1).min(y0.max(y1)).min(z0.max(z1)).min(Vec4::splat(t_max));
                let mut mask = near.cmple(far).bitmask();
                match mask.count_ones() {
                    0 => {}
                    1 => {
                        current = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    _ => {
                        // Sort the hit children by entry distance (at most 4: insertion sort),
                        // continue with the nearest and push the rest, farthest first.
                        let mut hit = [(0u32, 0f32); 4];
                        let mut m = 0;
                        while mask != 0 {
                            let i = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            let entry = (node.child[i], near[i]);
                            let mut j = m;
                            while j > 0 && hit[j - 1].1 > entry.1 {
                                hit[j] = hit[j - 1];
                                j -= 1;
                            }
                            hit[j] = entry;
                            m += 1;
                        }
                        for k in (1..m).rev() {
                            stack[sp] = hit[k];
                            sp += 1;
                        }
                        current = hit[0].0;
                        continue;
                    }
                }
            } else if current != EMPTY {
                let first = (current & ((1 << 27) - 1)) as usize;
                let count = (((current >> 27) & 0xF) + 1) as usize;
                t_max = leaf(first, count, t_max);
                if t_max < 0.0 {
                    return;
                }
            }
            // Next: the nearest pushed entry still within reach.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let (r, entry) = stack[sp];
                if entry <= t_max {
                    current = r;
                    break;
                }
            }
        }
    }

    /// The slow twin of [`Bvh4::traverse`]'s culling: every leaf whose box the ray enters within
    /// `[0, t_max]`, found by scanning every node (no ordering, no pruning by hits). Tests check
    /// that the fast traversal reaches the same hits.
    pub fn leaves_entered(&self, ray: &CullRay) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        if self.root == EMPTY {
            return out;
        }
        if self.root & LEAF != 0 {
            out.push(((self.root & ((1 << 27) - 1)) as usize, (((self.root >> 27) & 0xF) + 1) as usize));
            return out;
        }
        let mut stack = vec![self.root];
        while let Some(r) = stack.pop() {
            let node = &self.nodes[r as usize];
            for i in 0..4 {
                let c = node.child[i];
                if c == EMPTY {
                    continue;
                }
                let (lo, hi) = ([node.lo_x[i], node.lo_y[i], node.lo_z[i]], [node.hi_x[i], node.hi_y[i], node.hi_z[i]]);
                let (o, inv) = ([ray.ox.x, ray.oy.x, ray.oz.x], [ray.ix.x, ray.iy.x, ray.iz.x]);
                let (mut t0, mut t1) = (0f32, ray.t_max);
                for k in 0..3 {
                    let (a, b) = ((lo[k] - o[k]) * inv[k], (hi[k] - o[k]) * inv[k]);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
                if t0 <= t1 {
                    if c & LEAF != 0 {
                        out.push(((c & ((1 << 27) - 1)) as usize, (((c >> 27) & 0xF) + 1) as usize));
                    } else {
                        stack.push(c);
                    }
                }
            }
        }
        out
    }
}

/// Box of `items`, and box of their (doubled) centroids.
fn range_bounds(items: &[Item]) -> (Box4, Box4) {
    let (mut b, mut c) = (Box4::EMPTY, Box4::EMPTY);
    for it in items {
        b.grow(it);
        c.grow_point(it.center2());
    }
    (b, c)
}

/// SAH bins of the three axes: box and primitive count of each.
#[derive(Clone, Copy)]
struct Bins {
    boxes: [[Box4; BINS]; 3],
    counts: [[u32; BINS]; 3],
}

impl Bins {
    const EMPTY: Bins = Bins { boxes: [[Box4::EMPTY; BINS]; 3], counts: [[0; BINS]; 3] };

    fn merge(mut self, other: Bins) -> Bins {
        for axis in 0..3 {
            for b in 0..BINS {
                self.boxes[axis][b].grow_box(&other.boxes[axis][b]);
                self.counts[axis][b] += other.counts[axis][b];
            }
        }
        self
    }
}

/// One part of a node's primitives after splitting: its slots, its box and its centroid box.
#[derive(Clone, Copy)]
struct Part {
    start: usize,
    len: usize,
    bounds: Box4,
    cbounds: Box4,
}

/// Splits `items` (slots `offset..offset + items.len()`) in two: binned SAH over the (doubled)
/// centroid box `cb`, or the centroid median past [`SAH_MAX_DEPTH`] or when the SAH finds no
/// split. Reorders `items` in place and returns the two parts.
fn split(items: &mut [Item], offset: usize, cb: &Box4, depth: usize) -> (Part, Part) {
    let n = items.len();
    let extent = (cb.hi - cb.lo) * Vec4::new(1.0, 1.0, 1.0, 0.0);
    if depth < SAH_MAX_DEPTH && extent.max_element() > 0.0 {
        // Bin index = round((centroid - lo) * scale) in 0..=BINS-1, read off the mantissa of
        // that value plus 2^23 (cheaper than a checked float-to-int conversion; any monotonic
        // mapping works, as long as binning and partitioning use the same one).
        // Fewer bins for small nodes: the sweep over the bins costs as much as binning there.
        let nb = n.clamp(4, BINS);
        let scale = Vec4::select(extent.cmpgt(Vec4::ZERO), Vec4::splat((nb - 1) as f32) / extent, Vec4::ZERO);
        let lo = cb.lo * Vec4::new(1.0, 1.0, 1.0, 0.0);
        let bin_of = |it: &Item| {
            let b = (it.center2() - lo) * scale + Vec4::splat(MAGIC);
            [
                (b.x.to_bits() & BIN_MASK) as usize,
                (b.y.to_bits() & BIN_MASK) as usize,
                (b.z.to_bits() & BIN_MASK) as usize,
            ]
        };
        let bin_items = |bins: &mut Bins, items: &[Item]| {
            for it in items {
                let b = bin_of(it);
                for (axis, &bin) in b.iter().enumerate() {
                    bins.boxes[axis][bin].grow(it);
                    bins.counts[axis][bin] += 1;
                }
            }
        };
        let mut bins = Bins::EMPTY;
        if n >= PARALLEL_BINNING_MIN {
            use rayon::prelude::*;
            bins = items
                .par_chunks(PARALLEL_BINNING_MIN / 4)
                .map(|chunk| {
                    let mut b = Bins::EMPTY;
                    bin_items(&mut b, chunk);
                    b
                })
                .reduce(|| Bins::EMPTY, Bins::merge);
        } else if n >= ALL_AXES_MIN {
            bin_items(&mut bins, items);
        } else {
            // Small nodes: only the axis of the widest centroid spread (a third of the binning
            // work; the trees trace within 2% as fast, see docs/BVH.md).
            let axis = widest_axis(extent);
            for it in items.iter() {
                let bin = bin_of(it)[axis];
                bins.boxes[axis][bin].grow(it);
                bins.counts[axis][bin] += 1;
            }
        }
        let axes = if n >= ALL_AXES_MIN { 0..3 } else { widest_axis(extent)..widest_axis(extent) + 1 };
        let (boxes, counts) = (&bins.boxes, &bins.counts);
        let mut best = f32::INFINITY;
        let mut cut: Option<(usize, usize, Box4, Box4)> = None; // axis, first right bin, boxes
        for axis in axes {
            if extent[axis] <= 0.0 {
                continue;
            }
            // Right-to-left sweep: box and area x count of the right side for each cut.
            let mut right = [(Box4::EMPTY, 0f32); BINS];
            let (mut acc, mut count) = (Box4::EMPTY, 0u32);
            for b in (1..nb).rev() {
                acc.grow_box(&boxes[axis][b]);
                count += counts[axis][b];
                right[b] = (acc, acc.half_area() * count as f32);
            }
            let (mut acc, mut count) = (Box4::EMPTY, 0u32);
            for b in 1..nb {
                acc.grow_box(&boxes[axis][b - 1]);
                count += counts[axis][b - 1];
                if count == 0 || count as usize == n {
                    continue;
                }
                let cost = acc.half_area() * count as f32 + right[b].1;
                if cost < best {
                    best = cost;
                    cut = Some((axis, b, acc, right[b].0));
                }
            }
        }
        if let Some((axis, b, left_box, right_box)) = cut {
            // Partition, growing each side's centroid box on the way.
            let (mut lc, mut rc) = (Box4::EMPTY, Box4::EMPTY);
            let (mut i, mut j) = (0, n);
            while i < j {
                let it = items[i];
                let bin = (((it.center2()[axis] - lo[axis]) * scale[axis] + MAGIC).to_bits() & BIN_MASK) as usize;
                if bin < b {
                    lc.grow_point(it.center2());
                    i += 1;
                } else {
                    rc.grow_point(it.center2());
                    j -= 1;
                    items.swap(i, j);
                }
            }
            if i > 0 && i < n {
                return (
                    Part { start: offset, len: i, bounds: left_box, cbounds: lc },
                    Part { start: offset + i, len: n - i, bounds: right_box, cbounds: rc },
                );
            }
        }
    }
    // Centroid median on the widest axis (or by position when all centroids coincide).
    let axis = widest_axis(extent);
    let mid = n / 2;
    if extent[axis] > 0.0 {
        items.select_nth_unstable_by(mid, |a, b| a.center2()[axis].total_cmp(&b.center2()[axis]));
    }
    let (left, right) = items.split_at(mid);
    let (lb, lc) = range_bounds(left);
    let (rb, rc) = range_bounds(right);
    (
        Part { start: offset, len: mid, bounds: lb, cbounds: lc },
        Part { start: offset + mid, len: n - mid, bounds: rb, cbounds: rc },
    )
}

/// The axis (0, 1, 2) with the largest `extent`.
fn widest_axis(extent: Vec4) -> usize {
    if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    }
}

/// Builds the subtree over `items` (slots `offset..`), which has more than [`LEAF_MAX`]
/// primitives, into a new node array whose root is at index 0. Returns the array and the depth.
fn build_subtree(items: &mut [Item], offset: usize, cb: Box4, depth: usize) -> (Vec<Node>, usize) {
    if items.len() < PARALLEL_MIN {
        let mut nodes = Vec::with_capacity(items.len() / 2);
        let d = build_serial(items, offset, cb, depth, &mut nodes);
        return (nodes, d);
    }
    let (parts, m) = four_parts(items, offset, cb, depth);
    let parts = &parts[..m];
    // Split `items` into the parts' disjoint slices and build the big ones in parallel.
    let mut slices: Vec<(&mut [Item], &Part)> = Vec::with_capacity(4);
    let mut rest = items;
    for p in parts {
        let (head, tail) = rest.split_at_mut(p.len);
        slices.push((head, p));
        rest = tail;
    }
    let results: Vec<Option<(Vec<Node>, usize)>> = {
        use rayon::prelude::*;
        slices
            .into_par_iter()
            .map(|(s, p)| (p.len > LEAF_MAX).then(|| build_subtree(s, p.start, p.cbounds, depth + 1)))
            .collect()
    };
    let total: usize = 1 + results.iter().flatten().map(|r| r.0.len()).sum::<usize>();
    let mut nodes = Vec::with_capacity(total);
    nodes.push(Node::EMPTY);
    let mut root = Node::EMPTY;
    let mut max_depth = depth;
    for (i, (p, r)) in parts.iter().zip(results).enumerate() {
        match r {
            None => root.set(i, &p.bounds.aabb(), leaf_ref(p.start, p.len)),
            Some((sub, d)) => {
                let base = nodes.len() as u32;
                nodes.extend(sub.into_iter().map(|mut n| {
                    for c in &mut n.child {
                        if *c & LEAF == 0 {
                            *c += base;
                        }
                    }
                    n
                }));
                root.set(i, &p.bounds.aabb(), base);
                max_depth = max_depth.max(d);
            }
        }
    }
    nodes[0] = root;
    (nodes, max_depth)
}

/// Builds the subtree over `items` into `nodes` (its root appended first); returns the depth.
fn build_serial(items: &mut [Item], offset: usize, cb: Box4, depth: usize, nodes: &mut Vec<Node>) -> usize {
    let me = nodes.len();
    nodes.push(Node::EMPTY);
    let (parts, m) = four_parts(items, offset, cb, depth);
    let mut node = Node::EMPTY;
    let mut max_depth = depth;
    let mut rest = items;
    for (i, p) in parts[..m].iter().enumerate() {
        let (head, tail) = rest.split_at_mut(p.len);
        rest = tail;
        if p.len <= LEAF_MAX {
            node.set(i, &p.bounds.aabb(), leaf_ref(p.start, p.len));
        } else {
            let child = nodes.len() as u32;
            max_depth = max_depth.max(build_serial(head, p.start, p.cbounds, depth + 1, nodes));
            node.set(i, &p.bounds.aabb(), child);
        }
    }
    nodes[me] = node;
    max_depth
}

/// Splits a node's primitives into two, and each half with more than [`LEAF_MAX`] primitives
/// into two again: two to four parts, in slot order.
fn four_parts(items: &mut [Item], offset: usize, cb: Box4, depth: usize) -> ([Part; 4], usize) {
    let (a, b) = split(items, offset, &cb, depth);
    let none = Part { start: 0, len: 0, bounds: Box4::EMPTY, cbounds: Box4::EMPTY };
    let mut parts = [none; 4];
    let (left, right) = items.split_at_mut(a.len);
    let split_half =
        |half: Part, slice: &mut [Item]| (half.len > LEAF_MAX).then(|| split(slice, half.start, &half.cbounds, depth));
    let (l, r) = if a.len.min(b.len) >= PARALLEL_MIN {
        rayon::join(|| split_half(a, left), || split_half(b, right))
    } else {
        (split_half(a, left), split_half(b, right))
    };
    let mut m = 0;
    for (half, sub) in [(a, l), (b, r)] {
        match sub {
            Some((p, q)) => {
                parts[m] = p;
                parts[m + 1] = q;
                m += 2;
            }
            None => {
                parts[m] = half;
                m += 1;
            }
        }
    }
    (parts, m)
}

#[cfg(test)]
mod tests;
