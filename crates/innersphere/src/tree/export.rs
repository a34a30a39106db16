//! Writing the spheres of a tree for viewers: CSV and ASCII PLY (one vertex per sphere with
//! `radius` and `depth` properties, which e.g. MeshLab and ParaView can glyph as spheres).

use super::SphereTree;
use std::io::Write;

/// Which nodes to write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Which {
    /// Only the leaves (the inner spheres).
    Leaves,
    /// Every node.
    All,
}

fn nodes(tree: &SphereTree, which: Which) -> impl Iterator<Item = usize> + '_ {
    (0..tree.len()).filter(move |&n| which == Which::All || tree.is_leaf(n))
}

/// Writes `x,y,z,radius,depth` rows with a header.
pub fn write_csv(tree: &SphereTree, which: Which, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "x,y,z,radius,depth")?;
    for n in nodes(tree, which) {
        writeln!(
            out,
            "{},{},{},{},{}",
            tree.x[n], tree.y[n], tree.z[n], tree.r[n], tree.depth[n]
        )?;
    }
    Ok(())
}

/// Writes an ASCII PLY point cloud with `radius` and `depth` vertex properties.
pub fn write_ply(tree: &SphereTree, which: Which, out: &mut dyn Write) -> std::io::Result<()> {
    let count = nodes(tree, which).count();
    writeln!(
        out,
        "ply\nformat ascii 1.0\ncomment innersphere inner spheres"
    )?;
    writeln!(out, "element vertex {count}")?;
    writeln!(
        out,
        "property float x\nproperty float y\nproperty float z\nproperty float radius\nproperty ushort depth\nend_header"
    )?;
    for n in nodes(tree, which) {
        writeln!(
            out,
            "{} {} {} {} {}",
            tree.x[n], tree.y[n], tree.z[n], tree.r[n], tree.depth[n]
        )?;
    }
    Ok(())
}
