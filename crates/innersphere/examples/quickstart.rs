//! The smallest complete use of the library, on generated models (no files needed): build two
//! trees, make a pair, and ask it for distance, first contact, contact points and penetration
//! as one body moves toward the other. `cargo run --release -p innersphere --example
//! quickstart`.

use innersphere::{shapes, BuildOptions, MultipointOptions, Pair, Pose, SphereTree};

fn main() -> innersphere::Result<()> {
    // Two molars whose cusps meet at the identity pose (from files: `Mesh::load(path)?`).
    let (upper, lower) = shapes::tooth_pair(4);
    let opts = BuildOptions::default();
    let (a, b) = (
        SphereTree::build(&upper, &opts)?,
        SphereTree::build(&lower, &opts)?,
    );
    println!(
        "trees: {} and {} inner spheres",
        a.leaf_count(),
        b.leaf_count()
    );
    let mut pair = Pair::new(a, b);
    // Body A stays at the identity; body B rises from 1.5 units below into the bite.
    for step in 0..=4 {
        let lift = -1.5 + 0.5 * step as f64;
        let pose_b = Pose::from_translation([0.0, 0.0, lift].into());
        let d = pair.distance(&Pose::IDENTITY, &pose_b);
        let c = pair.contact(&Pose::IDENTITY, &pose_b);
        let m = pair.multipoint(&Pose::IDENTITY, &pose_b, &MultipointOptions::default());
        let p = pair.penetration(&Pose::IDENTITY, &pose_b);
        println!(
            "B at z {lift:+.1}: distance {:.4}, contact {}, {} contact points, \
             overlap volume {:.3e} units³ in {} patches, force on B ({:.2e}, {:.2e}, {:.2e})",
            d.distance,
            c.in_contact(),
            m.count,
            p.volume,
            pair.patches().len(),
            p.force.x,
            p.force.y,
            p.force.z,
        );
    }
    Ok(())
}
