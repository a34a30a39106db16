//! Fuzz targets of the planning commands' small inputs: teeth-axes JSON (`ist occlusion-map
//! --teeth-a/-b`, `ist view`), landmarks (`ist occlude --landmarks`, read through the
//! library's bounded text reader) and option strings (`--pose`, `--from`, `--reference`,
//! `--pose-b`, `--preset`, `--scenario`, `--device-class`).

use std::io::Read;
use std::path::Path;
use std::sync::OnceLock;

use innersphere::build::Preset;
use innersphere::input::{read_text_from, TextInput};
use innersphere::{shapes, Error, Mesh, Pose};
use innersphere_dental::contact_map::{check_pair, ArchContext, Jaw, Teeth, TeethFit};
use innersphere_haptic::DeviceClass;
use innersphere_motion::Scenario;

/// The generated arch pair the teeth are checked against (6 teeth per arch, coarse), made
/// once per process.
fn arches() -> &'static (Mesh, Mesh) {
    static ARCHES: OnceLock<(Mesh, Mesh)> = OnceLock::new();
    ARCHES.get_or_init(|| shapes::arch_pair(0, 6))
}

/// What every fit must satisfy on an arch of `n` vertices: a region per vertex, each a tooth
/// of the file or none, counts that add up, warnings naming the file.
fn check_fit(fit: &TeethFit, teeth: &Teeth, n: usize) {
    assert_eq!(fit.regions.len(), n, "one region per vertex");
    assert_eq!(fit.vertices.len(), teeth.teeth.len(), "one count per tooth");
    let labelled = fit.regions.iter().filter(|&&r| r != u32::MAX).count();
    assert_eq!(
        fit.vertices.iter().sum::<usize>(),
        labelled,
        "the counts add up to the labelled vertices"
    );
    assert!(
        fit.regions
            .iter()
            .all(|&r| r == u32::MAX || (r as usize) < teeth.teeth.len()),
        "a region names no tooth of the file"
    );
    assert!(
        2 * fit.vertices.iter().filter(|&&c| c == 0).count() <= teeth.teeth.len(),
        "a file most of whose teeth label nothing was accepted"
    );
    assert_eq!(fit.jaw, teeth.jaw().expect("an accepted file is one arch"));
    for w in &fit.warnings {
        assert!(w.contains(&teeth.source.display().to_string()), "{w}");
    }
}

/// Every property of a parsed teeth file: sorted unique numbers 1–32, finite centres, its
/// JSON reads back to it, no key of the text given twice, scaling by 2 doubles the centres,
/// and its checks against the generated arches (as either arch, with the other opposing)
/// answer without a panic, with a consistent fit when they accept.
fn check_teeth(t: &Teeth, text: &str) {
    assert!(!t.teeth.is_empty(), "a file without teeth was accepted");
    for w in t.teeth.windows(2) {
        assert!(w[0].number < w[1].number, "numbers not sorted and unique");
    }
    for tooth in &t.teeth {
        assert!((1..=32).contains(&tooth.number), "tooth {}", tooth.number);
        assert!(
            tooth.centre.is_finite(),
            "tooth {}: not finite",
            tooth.number
        );
    }
    match Teeth::from_json(&t.to_json(), &t.source) {
        Ok(back) => assert!(back == *t, "the teeth's JSON reads back different"),
        Err(e) => panic!("the teeth's JSON does not read back: {e}"),
    }
    // A reader that keeps the last of two equal keys sees as many keys as there are teeth.
    if let Ok(serde_json::Value::Object(map)) = serde_json::from_str(text) {
        assert_eq!(map.len(), t.teeth.len(), "a key given twice was accepted");
    }
    if let Ok(double) = t.scaled(2.0) {
        for (a, b) in t.teeth.iter().zip(&double.teeth) {
            assert!(b.centre == a.centre * 2.0 && a.number == b.number);
        }
    }
    let (upper, lower) = arches();
    for (arch, other, pose) in [
        (upper, lower, Pose::IDENTITY),
        (lower, upper, Pose::IDENTITY),
    ] {
        if let Ok((Some(fit), None)) = check_pair(arch, Some(t), other, None, &pose) {
            check_fit(&fit, t, arch.vertices.len());
        }
    }
    // A declared arch: the other arch's teeth are never accepted.
    if let Ok(jaw) = t.jaw() {
        let r = t.check_against(&ArchContext {
            arch: upper,
            opposing: None,
            jaw: Some(jaw.other()),
        });
        assert!(r.is_err(), "{:?} teeth accepted for the other arch", jaw);
    }
}

/// Teeth-axes JSON (the bytes as UTF-8): an accepted file satisfies [`check_teeth`]; a
/// refusal is an [`Error::Input`] naming the file.
pub fn teeth_json(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let name = Path::new("fuzz.json");
    match Teeth::from_json(text, name) {
        Ok(t) => check_teeth(&t, text),
        Err(Error::Input { path, .. }) => assert_eq!(path, name),
        Err(e) => panic!("a teeth file refused with another error than Input: {e}"),
    }
}

/// A reader that hands out at most `step` bytes a call (so that characters and NULs fall on
/// chunk borders).
struct Dribble<'a> {
    data: &'a [u8],
    step: usize,
}

impl Read for Dribble<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.step.min(buf.len()).min(self.data.len());
        buf[..n].copy_from_slice(&self.data[..n]);
        self.data = &self.data[n..];
        Ok(n)
    }
}

/// The most bytes the landmarks target reads (the real limit, 1 MiB, is beyond a fuzzer's
/// inputs).
const LANDMARK_LIMIT: u64 = 2048;

/// Landmarks as `ist occlude --landmarks` reads them: the first byte sets how many bytes a
/// read hands out (1–16), the rest is the file, read by the bounded text reader with a
/// 2048-byte limit. The reader must return exactly the bytes when they are at most the limit,
/// UTF-8 and free of NUL (checked independently here), and refuse them otherwise with an
/// [`Error::Input`]; the text is then parsed as teeth ([`check_teeth`]) and checked against
/// the generated lower arch as a point cloud (what `occlude` has of a body given as a tree).
pub fn landmarks(data: &[u8]) {
    let Some((&step, file)) = data.split_first() else {
        return;
    };
    let kind = TextInput {
        what: "landmarks file",
        max_bytes: LANDMARK_LIMIT,
    };
    let mut src = Dribble {
        data: file,
        step: usize::from(step % 16) + 1,
    };
    let name = Path::new("fuzz-landmarks.json");
    let read = read_text_from(&mut src, name, kind, file.len() as u64);
    let valid = file.len() as u64 <= LANDMARK_LIMIT
        && !file.contains(&0)
        && std::str::from_utf8(file).is_ok();
    let text = match read {
        Ok(text) => {
            assert!(
                valid,
                "the bounded reader accepted {} bytes it must refuse",
                file.len()
            );
            assert!(
                text.as_bytes() == file,
                "the bounded reader changed the text"
            );
            text
        }
        Err(Error::Input { path, message }) => {
            assert!(!valid, "the bounded reader refused valid text: {message}");
            assert_eq!(path, name);
            return;
        }
        Err(e) => panic!("the bounded reader failed with another error than Input: {e}"),
    };
    let Ok(t) = Teeth::from_json(&text, name) else {
        return;
    };
    check_teeth(&t, &text);
    let (upper, lower) = arches();
    let cloud = |m: &Mesh| Mesh {
        vertices: m.vertices.clone(),
        triangles: Vec::new(),
    };
    let (b, a) = (cloud(lower), cloud(upper));
    if let Ok(fit) = t.check_against(&ArchContext {
        arch: &b,
        opposing: Some((&a, Pose::IDENTITY)),
        jaw: None,
    }) {
        check_fit(&fit, &t, b.vertices.len());
        let _ = Jaw::of(t.teeth[0].number);
    }
}

/// Option strings of the planning commands (the bytes as UTF-8): the first character picks
/// the parser — `p` a pose (`--pose`, `--from`, `--reference`, `--pose-b`: the
/// [`pose_text`](crate::pose_text) oracle), `r` a build preset, `s` a motion scenario, `d` a
/// haptic device class. An accepted preset, scenario or class reads back from its name; a
/// refusal is an error, never a panic.
pub fn option_text(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let mut chars = text.chars();
    let Some(kind) = chars.next() else {
        return;
    };
    let rest = chars.as_str();
    match kind {
        'p' => crate::pose_text(rest.as_bytes()),
        'r' => {
            if let Ok(p) = rest.parse::<Preset>() {
                assert_eq!(p.name().parse::<Preset>().ok(), Some(p));
            }
        }
        's' => {
            if let Ok(s) = rest.parse::<Scenario>() {
                assert_eq!(s.to_string().parse::<Scenario>().ok(), Some(s));
            }
        }
        'd' => {
            if let Ok(d) = rest.parse::<DeviceClass>() {
                assert_eq!(d.to_string().parse::<DeviceClass>().ok(), Some(d));
            }
        }
        _ => {}
    }
}
