use innersphere::{Pair, Pose, SharedTree};
fn main() {
    let a = SharedTree::new(innersphere::tree::file::load("/tmp/maxilla.ist".as_ref()).unwrap());
    let b = SharedTree::new(innersphere::tree::file::load("/tmp/mandible.ist".as_ref()).unwrap());
    let m = innersphere_eval::motion::Motion::load("/work/shared/data/motion/jaw_chew_demo.csv")
        .unwrap();
    let mut carried = Pair::new(a.clone(), b.clone());
    let mut fresh = Pair::new(a.clone(), b.clone());
    let (mut dd, mut dc, mut dp, mut dpf) = (0, 0, 0, 0);
    for f in &m.frames {
        let p = &f.pose;
        let x = carried.distance(&Pose::IDENTITY, p).distance;
        fresh.reset();
        let y = fresh.distance(&Pose::IDENTITY, p).distance;
        if x.to_bits() != y.to_bits() {
            dd += 1;
        }
        let x = carried.contact(&Pose::IDENTITY, p).in_contact();
        fresh.reset();
        let y = fresh.contact(&Pose::IDENTITY, p).in_contact();
        if x != y {
            dc += 1;
        }
        let x = carried.penetration(&Pose::IDENTITY, p);
        fresh.reset();
        let y = fresh.penetration(&Pose::IDENTITY, p);
        if x.volume.to_bits() != y.volume.to_bits() {
            dp += 1;
        }
        if x.force != y.force
            || x.torque_b != y.torque_b
            || x.normal != y.normal
            || x.max_depth != y.max_depth
            || x.pairs != y.pairs
        {
            dpf += 1;
        }
    }
    println!(
        "frames {} distance diff {dd} contact diff {dc} pen volume diff {dp} pen other diff {dpf}",
        m.frames.len()
    );
}
