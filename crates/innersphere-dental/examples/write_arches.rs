//! Writes the generated arch pairs the planning tools are tried on, into a folder:
//! `upper.stl`/`lower.stl` (teeth with roots, `shapes::arch_pair`, mm, +z up, interlocking
//! at the identity), `upper_open.stl`/`lower_open.stl` (the roots cut off: open boundaries),
//! `upper_m.stl`/`lower_m.stl` (in metres), `upper_y.stl`/`lower_y.stl` (+y up),
//! `upper_bone.stl`/`lower_bone.stl` (the same teeth in a solid horseshoe of bone,
//! `shapes::arch_pair_with_bone`), `teeth_upper.stl`/`teeth_lower.stl` (those teeth alone on
//! the same grid), and the teeth files `upper.json`/`lower.json`.
//!
//! `cargo run --release -p innersphere-dental --example write_arches -- DIR`

use innersphere::glam::{DQuat, DVec3};
use innersphere::{shapes, Mesh};
use innersphere_dental::contact_map::Teeth;
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).ok_or("usage: write_arches DIR")?;
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir)?;
    let save = |m: &Mesh, name: &str| innersphere::mesh::save_stl(m, &dir.join(name));
    let map = |m: &Mesh, f: &dyn Fn(DVec3) -> DVec3| Mesh {
        vertices: m.vertices.iter().map(|v| f(*v)).collect(),
        triangles: m.triangles.clone(),
    };
    let (a, b) = shapes::arch_pair(3, 12);
    save(&a, "upper.stl")?;
    save(&b, "lower.stl")?;
    // Open boundaries: the root ends cut off (the upper roots reach up, the lower down).
    let cut = |m: &Mesh, keep: &dyn Fn(f64) -> bool| {
        let mut m = m.clone();
        m.triangles
            .retain(|t| keep(t.iter().map(|&i| m.vertices[i as usize].z).sum::<f64>() / 3.0));
        m
    };
    save(&cut(&a, &|z| z < 9.0), "upper_open.stl")?;
    save(&cut(&b, &|z| z > -4.0), "lower_open.stl")?;
    save(&map(&a, &|v| v * 1e-3), "upper_m.stl")?;
    save(&map(&b, &|v| v * 1e-3), "lower_m.stl")?;
    let q = DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2);
    save(&map(&a, &|v| q * v), "upper_y.stl")?;
    save(&map(&b, &|v| q * v), "lower_y.stl")?;
    let (ba, bb) = shapes::arch_pair_with_bone(3, 12);
    save(&ba, "upper_bone.stl")?;
    save(&bb, "lower_bone.stl")?;
    let (ta, tb) = shapes::arch_pair_teeth_extracted(3, 12);
    save(&ta, "teeth_upper.stl")?;
    save(&tb, "teeth_lower.stl")?;
    let (tu, tl) = Teeth::of_arch_pair(12);
    std::fs::write(dir.join("upper.json"), tu.to_json())?;
    std::fs::write(dir.join("lower.json"), tl.to_json())?;
    println!("wrote the generated arches into {}", dir.display());
    Ok(())
}
