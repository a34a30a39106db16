//! The generated seeds are valid inputs (but the one near miss each target keeps on
//! purpose), so that fuzzing starts from files that reach the end of each reader.

use std::io::Read;
use std::path::Path;

use innersphere::mesh::{load_bytes, Format};
use innersphere_fuzz::seeds::seeds;

fn loads(bytes: &[u8], format: Format) -> bool {
    load_bytes(bytes, format, Path::new("seed")).is_ok()
}

fn prefixed(prefix: &[u8], rest: &[u8]) -> Vec<u8> {
    let mut v = prefix.to_vec();
    v.extend_from_slice(rest);
    v
}

#[test]
fn mesh_seeds_load() {
    let stl = seeds("mesh_stl_binary");
    let ok: Vec<bool> = stl.iter().map(|s| loads(s, Format::Stl)).collect();
    assert_eq!(
        ok,
        [true, true, true, false],
        "the last one lies about its count"
    );
    for s in seeds("mesh_stl_ascii") {
        assert!(loads(&s, Format::Stl));
    }
    for s in seeds("mesh_obj") {
        assert!(loads(&s, Format::Obj));
    }
    for s in seeds("mesh_off") {
        assert!(loads(&s, Format::Off), "{}", String::from_utf8_lossy(&s));
    }
    for s in seeds("mesh_ply_ascii") {
        let file = prefixed(b"ply\nformat ascii 1.0\n", &s);
        if let Err(e) = load_bytes(&file, Format::Ply, Path::new("seed")) {
            panic!("{e}");
        }
    }
    for s in seeds("mesh_ply_binary") {
        let order: &[u8] = if s[0] % 2 == 0 {
            b"ply\nformat binary_little_endian 1.0\n"
        } else {
            b"ply\nformat binary_big_endian 1.0\n"
        };
        if let Err(e) = load_bytes(&prefixed(order, &s[1..]), Format::Ply, Path::new("seed")) {
            panic!("{e}");
        }
    }
    let formats = [Format::Stl, Format::Obj, Format::Ply, Format::Off];
    for s in seeds("mesh_gzip") {
        let format = formats[(s[0] & 3) as usize];
        let plain = if s[0] & 4 == 0 {
            let mut out = Vec::new();
            flate2::read::MultiGzDecoder::new(&s[1..])
                .read_to_end(&mut out)
                .expect("valid gzip");
            out
        } else {
            s[2..].to_vec()
        };
        assert!(loads(&plain, format));
    }
}

#[test]
fn other_seeds_load() {
    let trees = seeds("tree_file");
    assert_eq!(trees.len(), 3, "two hand-made trees and a built one");
    for s in trees {
        innersphere::tree::file::from_bytes(&s).expect("a valid tree file");
    }
    for s in seeds("motion_csv") {
        let text = std::str::from_utf8(&s).expect("UTF-8");
        innersphere_motion::Motion::parse(text, "seed").expect("a valid motion");
    }
    for s in seeds("pose_text") {
        let text = std::str::from_utf8(&s).expect("UTF-8");
        text.parse::<innersphere::Pose>().expect("a valid pose");
    }
    // The teeth seeds: the generated arches' own files fit them (the fuzzer starts from
    // accepted files, so that it reaches the checks), the near misses are refused.
    use innersphere_dental::contact_map::{check_pair, Teeth};
    let (upper, lower) = innersphere::shapes::arch_pair(0, 6);
    let teeth = seeds("teeth_json");
    let parsed: Vec<_> = teeth
        .iter()
        .map(|s| Teeth::from_json(std::str::from_utf8(s).unwrap(), "seed".as_ref()))
        .collect();
    let (tu, tl, full) = (
        parsed[0].as_ref().unwrap(),
        parsed[1].as_ref().unwrap(),
        parsed[2].as_ref().unwrap(),
    );
    assert_eq!(tl, full, "the axes' end points change nothing");
    let pose = innersphere::Pose::IDENTITY;
    check_pair(&upper, Some(tu), &lower, Some(tl), &pose).expect("the arches' own teeth fit");
    for (i, r) in parsed.iter().enumerate().skip(3) {
        let fits = r
            .as_ref()
            .is_ok_and(|t| check_pair(&upper, None, &lower, Some(t), &pose).is_ok());
        assert!(
            !fits,
            "teeth seed {i} is a near miss, yet it fits the lower arch"
        );
    }
}
