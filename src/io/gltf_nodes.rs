//! glTF 2.0 node hierarchy (glTF 2.0 specification, sec. 3.5 "Scenes" and "Nodes"): the nodes a
//! scene starts from, each node's local matrix (`matrix`, or translation/rotation/scale) composed
//! in `f64` into world matrices, cycles refused, and the expanded size (instances, triangles,
//! vertices) checked against the memory budget before anything is expanded.

use std::path::Path;

use glam::{DMat4, DQuat, DVec3};
use gltf::mesh::Mode;

use crate::error::{Error, Result};

/// Most mesh instances a node hierarchy may expand to (guards against exponential node graphs).
const MAX_INSTANCES: usize = 1_000_000;

/// The nodes the scene starts from: the default scene's (else the first scene's; else every
/// node that is no other node's child).
fn roots(doc: &gltf::Document) -> Vec<gltf::Node<'_>> {
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().count()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    }
}

/// What a node's subtree expands to: mesh instances, triangles and vertices.
#[derive(Clone, Copy, Default)]
struct Expanded {
    instances: u64,
    triangles: u64,
    vertices: u64,
}

impl Expanded {
    fn add(self, o: Expanded) -> Expanded {
        Expanded {
            instances: self.instances.saturating_add(o.instances),
            triangles: self.triangles.saturating_add(o.triangles),
            vertices: self.vertices.saturating_add(o.vertices),
        }
    }
}

/// The triangles and vertices of one instance of `mesh`, from its accessors' counts.
fn mesh_size(mesh: &gltf::Mesh) -> Expanded {
    let mut e = Expanded { instances: 1, ..Default::default() };
    for prim in mesh.primitives() {
        let vertices = prim.get(&gltf::Semantic::Positions).map_or(0, |a| a.count() as u64);
        let corners = prim.indices().map_or(vertices, |a| a.count() as u64);
        let triangles = match prim.mode() {
            Mode::Triangles => corners / 3,
            Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
            _ => 0,
        };
        e.triangles = e.triangles.saturating_add(triangles);
        e.vertices = e.vertices.saturating_add(vertices);
    }
    e
}

/// Refuses a node graph whose expansion (every mesh instance as triangles) would not fit in
/// the memory budget, or has over [`MAX_INSTANCES`] nodes. The graph is walked with counts
/// (each node's subtree summed once, children first), never expanded: a graph that instances a
/// mesh 2^18 times through doubling nodes costs one step per node and edge.
pub(super) fn check_expanded_size(path: &Path, doc: &gltf::Document) -> Result<()> {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut size: Vec<Option<Expanded>> = vec![None; nodes.len()];
    let mut on_path = vec![false; nodes.len()];
    let mut total = Expanded::default();
    for root in roots(doc) {
        // Iterative depth-first walk: (node, whether its children are done).
        let mut stack = vec![(root.index(), false)];
        while let Some((i, children_done)) = stack.pop() {
            if children_done {
                on_path[i] = false;
                let own = nodes[i].mesh().map_or(Expanded { instances: 1, ..Default::default() }, |m| mesh_size(&m));
                let sum = nodes[i].children().fold(own, |acc, c| acc.add(size[c.index()].unwrap_or_default()));
                size[i] = Some(sum);
                continue;
            }
            if size[i].is_some() {
                continue;
            }
            if on_path[i] {
                return Err(Error::parse(
                    path,
                    format!("nodes[{i}]: is its own ancestor (the node hierarchy has a cycle)"),
                ));
            }
            on_path[i] = true;
            stack.push((i, true));
            for c in nodes[i].children() {
                if on_path[c.index()] {
                    return Err(Error::parse(
                        path,
                        format!("nodes[{}]: is its own ancestor (the node hierarchy has a cycle)", c.index()),
                    ));
                }
                if size[c.index()].is_none() {
                    stack.push((c.index(), false));
                }
            }
        }
        total = total.add(size[root.index()].unwrap_or_default());
    }
    if total.instances > MAX_INSTANCES as u64 {
        return Err(Error::parse(
            path,
            format!("nodes: the node hierarchy expands to over {MAX_INSTANCES} nodes ({} counted)", total.instances),
        ));
    }
    let mut estimate = crate::budget::Estimate::default();
    let what = format!(
        "the meshes of every node instance expanded ({} triangles, {} vertices)",
        total.triangles, total.vertices
    );
    estimate.add(what.clone(), "nodes", total.triangles, crate::budget::MESH_BYTES_PER_TRIANGLE);
    estimate.add(what, "nodes", total.vertices, crate::budget::MESH_BYTES_PER_VERTEX);
    estimate.check_memory(&crate::budget::memory_budget(), &path.display().to_string())
}

/// Every node of the scene with its world matrix, depth first.
pub(super) fn instances<'a>(path: &Path, doc: &'a gltf::Document) -> Result<Vec<(gltf::Node<'a>, DMat4)>> {
    let roots = roots(doc);
    let mut out = Vec::new();
    let mut on_path = vec![false; doc.nodes().count()];
    for root in roots {
        visit(path, root, DMat4::IDENTITY, &mut on_path, &mut out)?;
    }
    Ok(out)
}

fn visit<'a>(
    path: &Path,
    node: gltf::Node<'a>,
    parent: DMat4,
    on_path: &mut [bool],
    out: &mut Vec<(gltf::Node<'a>, DMat4)>,
) -> Result<()> {
    let i = node.index();
    if on_path[i] {
        return Err(Error::parse(path, format!("nodes[{i}]: is its own ancestor (the node hierarchy has a cycle)")));
    }
    if out.len() >= MAX_INSTANCES {
        return Err(Error::parse(
            path,
            format!("nodes[{i}]: the node hierarchy expands to over {MAX_INSTANCES} nodes"),
        ));
    }
    let local = node_matrix(path, &node)?;
    let world = parent * local;
    on_path[i] = true;
    let children: Vec<gltf::Node<'a>> = node.children().collect();
    out.push((node, world));
    for child in children {
        visit(path, child, world, on_path, out)?;
    }
    on_path[i] = false;
    Ok(())
}

/// A node's local matrix in `f64`: its `matrix`, or `T * R * S`.
fn node_matrix(path: &Path, node: &gltf::Node) -> Result<DMat4> {
    let i = node.index();
    let f = |v: f32| f64::from(v);
    let m = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => DMat4::from_cols_array_2d(&matrix.map(|col| col.map(f))),
        gltf::scene::Transform::Decomposed { translation: t, rotation: r, scale: s } => {
            let q = DQuat::from_xyzw(f(r[0]), f(r[1]), f(r[2]), f(r[3]));
            if !(q.is_finite() && q.length() > 0.0) {
                return Err(Error::parse(
                    path,
                    format!("nodes[{i}].rotation: not a finite non-zero quaternion: {r:?}"),
                ));
            }
            DMat4::from_scale_rotation_translation(
                DVec3::new(f(s[0]), f(s[1]), f(s[2])),
                q.normalize(),
                DVec3::new(f(t[0]), f(t[1]), f(t[2])),
            )
        }
    };
    if !m.is_finite() {
        return Err(Error::parse(path, format!("nodes[{i}]: transform has a non-finite value")));
    }
    Ok(m)
}
