mod common;
use innersphere::motion::*;
use std::time::Instant;

fn stats(g: &Generated, b: &innersphere::Mesh) {
    let c = g.counts();
    eprintln!("frames {} sep {} touch {} overlap {} bite_c {:.4} scale {:.3} touch {:.3} samples {} tremor {:.4}", g.motion.len(), c.separated, c.touching, c.overlap, g.bite_clearance, g.scale, g.touch, g.samples, g.tremor_rms);
    let (lo, hi) = b.bbox();
    let pts = [lo, hi, (lo + hi) * 0.5, innersphere::glam::DVec3::new(lo.x, hi.y, lo.z)];
    let mut vmax: f64 = 0.0; let mut amax: f64 = 0.0;
    let f = &g.motion.frames;
    for p in pts {
        for i in 2..f.len() {
            let x0 = f[i-2].pose.transform_point(p); let x1 = f[i-1].pose.transform_point(p); let x2 = f[i].pose.transform_point(p);
            vmax = vmax.max((x2 - x1).length() * 1000.0);
            amax = amax.max((x2 - 2.0 * x1 + x0).length() * 1e6);
        }
    }
    eprintln!("vmax {vmax:.1} amax {amax:.1}");
    let line: String = g.clearance.iter().step_by(50).map(|c| format!("{c:.2} ")).collect();
    eprintln!("{line}");
}

#[test]
#[ignore]
fn scratch_tooth() {
    let (a, b) = innersphere::shapes::tooth_pair(4);
    for sc in Scenario::ALL {
        let t = Instant::now();
        let g = generate_with(sc, 5.0, 1, &a, &b, &GenerateOptions::default()).unwrap();
        eprintln!("{sc} {:?}", t.elapsed());
        stats(&g, &b);
    }
}

#[test]
#[ignore]
fn scratch_jaw() {
    let a = innersphere::mesh::io::load(&common::data("jaw/ofj_p26_maxilla_teeth.stl.gz")).unwrap();
    let b = innersphere::mesh::io::load(&common::data("jaw/ofj_p26_mandible_teeth.stl.gz")).unwrap();
    let f = AnatomicalFrame::from_meshes(&a, &b).unwrap();
    eprintln!("{f:?}");
    for sc in Scenario::ALL {
        let t = Instant::now();
        let g = generate_with(sc, 5.0, 1, &a, &b, &GenerateOptions::default()).unwrap();
        eprintln!("{sc} {:?}", t.elapsed());
        stats(&g, &b);
    }
}
