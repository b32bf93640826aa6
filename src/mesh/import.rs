//! Particles from files: polygon outlines in CSV and meshes in gmsh `.msh` files.
//!
//! # Outline CSV ([`read_outlines_csv`])
//!
//! One particle a block of lines, blocks separated by one or more blank lines:
//!
//! ```text
//! # two grains (mm); lines starting with '#' are comments
//! 0.0, 0.0
//! 4.0, 0.0
//! 4.0, 2.0      # a comment may also end a data line
//! 0.0, 2.0
//!
//! 6.0, 0.0
//! 9.0, 1.0
//! 7.0, 3.0
//! ```
//!
//! - every data line holds exactly two numbers `x, y` separated by a comma (a semicolon, tab or
//!   spaces also work);
//! - a line that is empty or only white space ends the current particle; comment lines (first
//!   non-blank character `#`) are skipped and do not end a particle; text after `#` on a data
//!   line is ignored;
//! - the vertices run around the outline in either direction; a last vertex equal to the first
//!   (a closed ring, as many tools write it) is dropped;
//! - each particle must be a simple polygon with at least 3 vertices (see
//!   [`super::polygon::check_simple_polygon`]); there is no header line.
//!
//! Errors name the line (1-based) and what was expected.
//!
//! # gmsh meshes ([`read_msh`])
//!
//! MSH 4.1, ASCII or binary (parsed with the `mshio` crate), as written by gmsh for a 2D model
//! in the x–y plane (z is ignored). Each physical group of dimension 2 is one particle: all
//! elements of the surfaces (entities) that carry the group's tag. Its name comes from
//! `$PhysicalNames` when present.
//!
//! - 4-node quadrilaterals are used as they are, turned counter-clockwise where they are not;
//! - 3-node triangles are split into three quadrilaterals each (through the centroid and the
//!   edge midpoints, see [`super::polygon::triangles_to_quads`]); when a group mixes triangles
//!   and quadrilaterals, its quadrilaterals are split into four (through their edge midpoints
//!   and centroid) so that the mesh stays conforming;
//! - any other element type in a group (second-order elements, ...) is an error, as are a
//!   group that is not one connected region (elements joined through shared edges), a
//!   degenerate or non-convex element, and an edge shared by more than two elements;
//! - the boundary is every element edge used once (body on the left), edge set `"boundary"`.
//!
//! Node tags that are not sparse are taken to number the nodes in the order of the node blocks
//! (how gmsh writes them).

use super::polygon::{check_simple_polygon, orient, triangles_to_quads};
use super::Mesh;
use std::collections::{BTreeMap, HashMap};

type P = [f64; 2];

// ---------------------------------------------------------------------------------------------
// CSV outlines

/// One particle of an outline CSV file.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvOutline {
    /// Lines (1-based) of the particle's first and last vertex.
    pub lines: [usize; 2],
    /// The vertices as read (mm; a repeated closing vertex removed).
    pub vertices: Vec<[f64; 2]>,
}

/// An error in an outline CSV file, at a line (1-based; 0 when not tied to a line).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", if *.line > 0 { format!("line {}: {}", .line, .message) } else { .message.clone() })]
pub struct CsvError {
    pub line: usize,
    pub message: String,
}

/// Reads the particles of an outline CSV text (format in the module docs).
///
/// # Errors
/// [`CsvError`] for a line that is not two finite numbers, a particle with fewer than 3
/// vertices or one that is not a simple polygon, and a file without any particle.
pub fn read_outlines_csv(text: &str) -> Result<Vec<CsvOutline>, CsvError> {
    let mut out = Vec::new();
    let mut current: Option<CsvOutline> = None;
    let finish = |block: CsvOutline, out: &mut Vec<CsvOutline>| -> Result<(), CsvError> {
        let mut v = block.vertices;
        if v.len() > 3 && v.first() == v.last() {
            v.pop();
        }
        let err = |message: String| CsvError { line: block.lines[0], message };
        let what = format!("particle {} (lines {}-{})", out.len(), block.lines[0], block.lines[1]);
        if v.len() < 3 {
            return Err(err(format!("{what} has {} vertices; expected at least 3 lines \"x, y\" per particle", v.len())));
        }
        check_simple_polygon(&v).map_err(|e| err(format!("{what}: {e}; expected a simple polygon")))?;
        out.push(CsvOutline { lines: block.lines, vertices: v });
        Ok(())
    };
    for (i, raw_line) in text.lines().enumerate() {
        let line_no = i + 1;
        let trimmed = raw_line.trim();
        if trimmed.starts_with('#') {
            continue;
        }
        if trimmed.is_empty() {
            if let Some(b) = current.take() {
                finish(b, &mut out)?;
            }
            continue;
        }
        let data = trimmed.split('#').next().unwrap_or("").trim();
        let fields: Vec<&str> = data
            .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        let nums: Option<Vec<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        let p = match nums {
            Some(v) if v.len() == 2 && v.iter().all(|x| x.is_finite()) => [v[0], v[1]],
            _ => {
                return Err(CsvError {
                    line: line_no,
                    message: format!("\"{data}\"; expected two finite numbers \"x, y\" (mm), a blank line between particles, or a '#' comment"),
                })
            }
        };
        match current.as_mut() {
            Some(b) => {
                b.vertices.push(p);
                b.lines[1] = line_no;
            }
            None => current = Some(CsvOutline { lines: [line_no, line_no], vertices: vec![p] }),
        }
    }
    if let Some(b) = current.take() {
        finish(b, &mut out)?;
    }
    if out.is_empty() {
        return Err(CsvError { line: 0, message: "no particle; expected blocks of lines \"x, y\" separated by blank lines".into() });
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// gmsh

/// One particle of a gmsh file: a physical group of dimension 2 and its mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MshParticle {
    /// The physical tag.
    pub tag: i32,
    /// The name from `$PhysicalNames`, if any.
    pub name: Option<String>,
    pub mesh: Mesh,
}

impl MshParticle {
    /// `physical group 2 "grain_b"` (or without the name).
    pub fn describe(&self) -> String {
        describe_group(self.tag, self.name.as_deref())
    }
}

fn describe_group(tag: i32, name: Option<&str>) -> String {
    match name {
        Some(n) => format!("physical group {tag} \"{n}\""),
        None => format!("physical group {tag}"),
    }
}

/// An error reading a gmsh file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MshError {
    #[error("not a readable MSH 4.1 file: {0}")]
    Parse(String),
    #[error("no physical group of dimension 2 with elements; expected each particle as a 2D physical group (Physical Surface in gmsh)")]
    NoSurfaceGroups,
    #[error("{group}: element type {element} is not supported; expected 3-node triangles or 4-node quadrilaterals (first order)")]
    UnsupportedElement { group: String, element: String },
    #[error("{group} is not one connected region ({parts} separate parts); expected one particle per physical group")]
    Disconnected { group: String, parts: usize },
    #[error("{group}: element {element} refers to node {node}, which is not in the file")]
    MissingNode { group: String, element: u64, node: u64 },
    #[error("{group}: element {element} is degenerate or not convex")]
    Degenerate { group: String, element: u64 },
    #[error("{group}: an edge is shared by more than two elements (nodes {0} and {1})", .edge[0], .edge[1])]
    NonManifold { group: String, edge: [u64; 2] },
}

/// Names of the physical groups from the `$PhysicalNames` section (`(dim, tag) → name`); the
/// section is text in ASCII and binary files alike.
fn physical_names(bytes: &[u8]) -> HashMap<(i32, i32), String> {
    let mut out = HashMap::new();
    let start_tag = b"$PhysicalNames";
    let Some(start) = bytes.windows(start_tag.len()).position(|w| w == start_tag) else { return out };
    let rest = &bytes[start + start_tag.len()..];
    let end_tag = b"$EndPhysicalNames";
    let Some(end) = rest.windows(end_tag.len()).position(|w| w == end_tag) else { return out };
    let text = String::from_utf8_lossy(&rest[..end]);
    for line in text.lines().skip(1) {
        let line = line.trim();
        let mut it = line.splitn(3, char::is_whitespace);
        let (Some(d), Some(t), Some(name)) = (it.next(), it.next(), it.next()) else { continue };
        if let (Ok(d), Ok(t)) = (d.parse::<i32>(), t.parse::<i32>()) {
            out.insert((d, t), name.trim().trim_matches('"').to_string());
        }
    }
    out
}

fn parse_error(e: &mshio::MshParserError<&[u8]>) -> String {
    let trace = e.filtered_backtrace();
    let mut parts: Vec<String> = trace
        .iter()
        .rev()
        .map(|(_, k)| k.context().map_or_else(|| k.to_string(), str::to_string))
        .collect();
    parts.dedup();
    if parts.is_empty() {
        "unknown parse error".into()
    } else {
        parts.join(": ")
    }
}

/// Reads the particles (2D physical groups) of a gmsh MSH 4.1 file, in order of their tags
/// (format and rules in the module docs).
///
/// # Errors
/// [`MshError`] when the file cannot be parsed, has no 2D physical group with elements, or a
/// group has an unsupported element type, a degenerate element, a non-manifold edge, or is not
/// one connected region.
pub fn read_msh(bytes: &[u8]) -> Result<Vec<MshParticle>, MshError> {
    let file = mshio::parse_msh_bytes(bytes).map_err(|e| MshError::Parse(parse_error(&e)))?;
    let names = physical_names(bytes);
    let Some(entities) = file.data.entities.as_ref() else { return Err(MshError::NoSurfaceGroups) };
    // physical tag -> surface tags
    let mut groups: BTreeMap<i32, Vec<i32>> = BTreeMap::new();
    for s in &entities.surfaces {
        for &g in &s.physical_tags {
            groups.entry(g).or_default().push(s.tag);
        }
    }
    // node tag -> coordinates
    let mut coords: HashMap<u64, P> = HashMap::new();
    if let Some(nodes) = file.data.nodes.as_ref() {
        let mut next = nodes.min_node_tag;
        for block in &nodes.node_blocks {
            match &block.node_tags {
                Some(map) => {
                    for (&tag, &i) in map {
                        if let Some(n) = block.nodes.get(i) {
                            coords.insert(tag, [n.x, n.y]);
                        }
                    }
                }
                None => {
                    for n in &block.nodes {
                        coords.insert(next, [n.x, n.y]);
                        next += 1;
                    }
                }
            }
        }
    }
    let blocks: Vec<_> = file
        .data
        .elements
        .as_ref()
        .map(|e| e.element_blocks.iter().filter(|b| b.entity_dim == 2).collect())
        .unwrap_or_default();
    let mut out = Vec::new();
    for (tag, surfaces) in groups {
        let name = names.get(&(2, tag)).cloned();
        let group = describe_group(tag, name.as_deref());
        let mut tris: Vec<(u64, [u64; 3])> = Vec::new();
        let mut quads: Vec<(u64, [u64; 4])> = Vec::new();
        for blk in blocks.iter().filter(|b| surfaces.contains(&b.entity_tag)) {
            for e in &blk.elements {
                match (blk.element_type, e.nodes.as_slice()) {
                    (mshio::ElementType::Tri3, &[a, b, c]) => tris.push((e.element_tag, [a, b, c])),
                    (mshio::ElementType::Qua4, &[a, b, c, d]) => quads.push((e.element_tag, [a, b, c, d])),
                    (kind, _) => {
                        return Err(MshError::UnsupportedElement { group, element: format!("{kind:?} (gmsh type {})", kind as i32) })
                    }
                }
            }
        }
        if tris.is_empty() && quads.is_empty() {
            continue;
        }
        let mesh = group_mesh(&group, &coords, &tris, &quads)?;
        out.push(MshParticle { tag, name, mesh });
    }
    if out.is_empty() {
        return Err(MshError::NoSurfaceGroups);
    }
    Ok(out)
}

/// The quadrilateral mesh of one group's triangles and quadrilaterals (node tags).
fn group_mesh(group: &str, coords: &HashMap<u64, P>, tris: &[(u64, [u64; 3])], quads: &[(u64, [u64; 4])]) -> Result<Mesh, MshError> {
    let mut local: HashMap<u64, usize> = HashMap::new();
    let mut nodes: Vec<P> = Vec::new();
    let mut node = |nodes: &mut Vec<P>, element: u64, tag: u64| -> Result<usize, MshError> {
        if let Some(&i) = local.get(&tag) {
            return Ok(i);
        }
        let p = coords.get(&tag).ok_or(MshError::MissingNode { group: group.to_string(), element, node: tag })?;
        local.insert(tag, nodes.len());
        nodes.push(*p);
        Ok(nodes.len() - 1)
    };
    let mut t3: Vec<[usize; 3]> = Vec::with_capacity(tris.len());
    for (id, t) in tris {
        let mut v = [node(&mut nodes, *id, t[0])?, node(&mut nodes, *id, t[1])?, node(&mut nodes, *id, t[2])?];
        let o = orient(nodes[v[0]], nodes[v[1]], nodes[v[2]]);
        let scale = super::polygon::size_of(&[nodes[v[0]], nodes[v[1]], nodes[v[2]]]);
        if o.abs() <= 1e-12 * scale * scale || !o.is_finite() {
            return Err(MshError::Degenerate { group: group.to_string(), element: *id });
        }
        if o < 0.0 {
            v.swap(1, 2);
        }
        t3.push(v);
    }
    let mut q4: Vec<[usize; 4]> = Vec::with_capacity(quads.len());
    for (id, q) in quads {
        let mut v = [node(&mut nodes, *id, q[0])?, node(&mut nodes, *id, q[1])?, node(&mut nodes, *id, q[2])?, node(&mut nodes, *id, q[3])?];
        let p = v.map(|i| nodes[i]);
        if super::polygon_area(p) < 0.0 {
            v.reverse();
        }
        let sj = super::quality::scaled_jacobian(v.map(|i| nodes[i]));
        if sj.is_nan() || sj <= 0.0 {
            return Err(MshError::Degenerate { group: group.to_string(), element: *id });
        }
        q4.push(v);
    }
    // edges: manifold, and the elements joined through them one region
    let n_el = t3.len() + q4.len();
    let mut parent: Vec<usize> = (0..n_el).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut edge_users: HashMap<[usize; 2], Vec<usize>> = HashMap::new();
    let polys = t3.iter().map(|t| t.to_vec()).chain(q4.iter().map(|q| q.to_vec()));
    for (e, poly) in polys.enumerate() {
        let k = poly.len();
        for i in 0..k {
            let (a, b) = (poly[i], poly[(i + 1) % k]);
            edge_users.entry([a.min(b), a.max(b)]).or_default().push(e);
        }
    }
    let tag_of: HashMap<usize, u64> = local.iter().map(|(&t, &i)| (i, t)).collect();
    for (edge, users) in &edge_users {
        if users.len() > 2 {
            return Err(MshError::NonManifold { group: group.to_string(), edge: edge.map(|i| tag_of.get(&i).copied().unwrap_or(0)) });
        }
        if let [a, b] = users[..] {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra] = rb;
        }
    }
    let parts = (0..n_el).filter(|&i| root(&mut parent, i) == i).count();
    if parts != 1 {
        return Err(MshError::Disconnected { group: group.to_string(), parts });
    }
    if t3.is_empty() {
        return Ok(Mesh::from_quads(nodes, q4));
    }
    if q4.is_empty() {
        return Ok(triangles_to_quads(nodes, &t3));
    }
    // mixed: triangles into three, quadrilaterals into four, sharing the edge midpoints
    let mut mid: HashMap<[usize; 2], usize> = HashMap::new();
    let mut midpoint = |nodes: &mut Vec<P>, a: usize, b: usize| -> usize {
        *mid.entry([a.min(b), a.max(b)]).or_insert_with(|| {
            let (p, q) = (nodes[a], nodes[b]);
            nodes.push([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]);
            nodes.len() - 1
        })
    };
    let mut elements = Vec::with_capacity(3 * t3.len() + 4 * q4.len());
    let polys: Vec<Vec<usize>> = t3.iter().map(|t| t.to_vec()).chain(q4.iter().map(|q| q.to_vec())).collect();
    for poly in polys {
        let k = poly.len();
        let m: Vec<usize> = (0..k).map(|i| midpoint(&mut nodes, poly[i], poly[(i + 1) % k])).collect();
        let c = poly.iter().fold([0.0, 0.0], |s, &i| [s[0] + nodes[i][0] / k as f64, s[1] + nodes[i][1] / k as f64]);
        let g = nodes.len();
        nodes.push(c);
        for i in 0..k {
            elements.push([poly[i], m[i], g, m[(i + k - 1) % k]]);
        }
    }
    Ok(Mesh::from_quads(nodes, elements))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_blocks_comments_and_errors() {
        let text = "# grains\n0,0\n1,0\n1,1 # corner\n0,1\n0,0\n\n\n# second\n5 0\n6;0\n5,1\n";
        let p = read_outlines_csv(text).unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].vertices.len(), 4, "closing vertex dropped");
        assert_eq!(p[0].lines, [2, 6]);
        assert_eq!(p[1].lines, [10, 12]);
        let e = read_outlines_csv("0,0\n1,0\n1,x\n").unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.to_string().starts_with("line 3: \"1,x\""), "{e}");
        let e = read_outlines_csv("0,0\n1,0\n\n0,1\n").unwrap_err();
        assert!(e.to_string().contains("at least 3"), "{e}");
        assert!(read_outlines_csv("# nothing\n").is_err());
        let e = read_outlines_csv("0,0\n2,2\n2,0\n0,1\n").unwrap_err();
        assert!(e.to_string().contains("not simple"), "{e}");
    }

    #[test]
    fn names_section() {
        let n = physical_names(b"$PhysicalNames\n2\n2 1 \"a b\"\n1 7 \"edge\"\n$EndPhysicalNames\n");
        assert_eq!(n.get(&(2, 1)).map(String::as_str), Some("a b"));
        assert_eq!(n.get(&(1, 7)).map(String::as_str), Some("edge"));
    }
}
