//! The HTTP API against the library, on the built-in scene: `POST /api/pose` answers what a
//! fresh pair answers (the same as `ist query`), the state streams, the loop runs, the
//! contact map is the library's, and bad requests get a 4xx with a message, never a panic or
//! a file outside the embedded ones.

use innersphere::{DistanceOptions, Pair, PenetrationOptions, Pose};
use innersphere_view::{serve, Scene, ServeOptions};
use serde_json::Value;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::OnceLock;
use std::time::Duration;

struct Server {
    addr: SocketAddr,
    scene: Scene,
}

fn server() -> &'static Server {
    static S: OnceLock<Server> = OnceLock::new();
    S.get_or_init(|| {
        let scene = Scene::demo().unwrap();
        let addr = serve_scene(scene.clone(), ServeOptions::default());
        Server { addr, scene }
    })
}

/// A server of `scene` on its own free port (the options' port is replaced).
fn serve_scene(scene: Scene, opts: ServeOptions) -> SocketAddr {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let opts = ServeOptions { port: 0, ..opts };
        serve(scene, opts, move |addr| tx.send(addr).unwrap()).unwrap();
    });
    rx.recv_timeout(Duration::from_secs(30)).unwrap()
}

/// (status, body) of one request to the shared server.
fn request(method: &str, path: &str, body: &str) -> (u16, Vec<u8>) {
    request_to(server().addr, method, path, body)
}

/// (status, body) of one request to the server at `addr`.
fn request_to(addr: SocketAddr, method: &str, path: &str, body: &str) -> (u16, Vec<u8>) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).unwrap();
    let text = String::from_utf8_lossy(&out);
    let code: u16 = text.split_whitespace().nth(1).unwrap().parse().unwrap();
    let start = out.windows(4).position(|w| w == b"\r\n\r\n").unwrap() + 4;
    let mut body = out[start..].to_vec();
    if text
        .to_ascii_lowercase()
        .contains("transfer-encoding: chunked")
    {
        body = dechunk(&body);
    }
    (code, body)
}

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let eol = b.windows(2).position(|w| w == b"\r\n").unwrap();
        let n = usize::from_str_radix(std::str::from_utf8(&b[..eol]).unwrap().trim(), 16).unwrap();
        if n == 0 {
            return out;
        }
        out.extend_from_slice(&b[eol + 2..eol + 2 + n]);
        b = &b[eol + 4 + n..];
    }
}

fn json(method: &str, path: &str, body: &str) -> (u16, Value) {
    let (c, b) = request(method, path, body);
    (c, serde_json::from_slice(&b).unwrap_or(Value::Null))
}

fn close(a: &Value, b: f64) -> bool {
    a.as_f64() == Some(b)
}

/// An answer's serde form.
fn form<T: serde::Serialize>(x: &T) -> serde_json::Value {
    serde_json::to_value(x).expect("answers serialize")
}

#[test]
fn a_posted_pose_is_answered_as_a_fresh_pair_answers() {
    let s = server();
    for p7 in [
        [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
        [0.2, -0.1, -0.3, 1.0, 0.02, 0.0, 0.0],
        [0.0, 0.0, -4.0, 1.0, 0.0, 0.0, 0.1],
    ] {
        let body = format!("{{\"pose_b\": {}}}", serde_json::to_string(&p7).unwrap());
        let (code, v) = json("POST", "/api/pose", &body);
        assert_eq!(code, 200, "{v}");
        let pose = Pose::from_array(p7).unwrap();
        let mut pair = Pair::new(s.scene.a.clone(), s.scene.b.clone());
        let d = pair.distance_with(
            &Pose::IDENTITY,
            &pose,
            &DistanceOptions {
                coherence: false,
                ..Default::default()
            },
        );
        let q = pair.penetration_with(
            &Pose::IDENTITY,
            &pose,
            &PenetrationOptions {
                safe_motion: false,
                ..Default::default()
            },
        );
        // Each answer is the library's serde form, bit for bit (a fresh pair, as `ist
        // query` runs).
        assert_eq!(v["distance"], form(&d), "{v}");
        let mut want = form(&q);
        want["patches"] = serde_json::json!(pair.patches());
        assert_eq!(v["penetration"], want, "{v}");
        // The demo's trees carry their meshes: the refined distance as well.
        let r = Pair::new(s.scene.a.clone(), s.scene.b.clone())
            .refined_distance(&Pose::IDENTITY, &pose)
            .unwrap();
        assert_eq!(v["refined_distance"], form(&r), "{v}");
        assert!(r.distance <= d.distance.max(0.0));
        // And the meshes' own penetration with its patches.
        let mut meshes = Pair::new(s.scene.a.clone(), s.scene.b.clone());
        let m = meshes
            .mesh_penetration_with(&Pose::IDENTITY, &pose, &Default::default())
            .unwrap();
        let mut want = form(&m);
        want["patches"] = serde_json::json!(meshes.patches());
        assert_eq!(v["mesh_penetration"], want, "{v}");
    }
}

/// `--contact mesh`: the loop's readout is the meshes' own penetration (the state says so),
/// and a scene whose trees do not carry their meshes is refused.
#[test]
fn mesh_contact_reads_out_the_meshes_volume() {
    let s = server();
    let opts = ServeOptions {
        contact: innersphere_haptic::ContactSource::Mesh,
        ..Default::default()
    };
    let addr = serve_scene(s.scene.clone(), opts);
    assert_eq!(
        request_to(addr, "POST", "/api/mode", r#"{"mode":"free"}"#).0,
        200
    );
    // B pressed into A: the pose the loop then answers for.
    let p7 = [0.0, 0.0, -0.05, 1.0, 0.0, 0.0, 0.0];
    let body = format!("{{\"pose_b\": {}}}", serde_json::to_string(&p7).unwrap());
    let (code, _) = request_to(addr, "POST", "/api/pose", &body);
    assert_eq!(code, 200);
    let pose = Pose::from_array(p7).unwrap();
    let want = Pair::new(s.scene.a.clone(), s.scene.b.clone())
        .mesh_penetration_with(&Pose::IDENTITY, &pose, &Default::default())
        .unwrap();
    assert!(want.contact, "{want:?}");
    let end = std::time::Instant::now() + Duration::from_secs(30);
    loop {
        let (_, b) = request_to(addr, "GET", "/api/state", "");
        let v: Value = serde_json::from_slice(&b).unwrap();
        assert_eq!(v["contact_source"], "mesh", "{v}");
        if v["pose_b"] == serde_json::json!(p7) && close(&v["volume"], want.volume) {
            assert_eq!(v["contact"], true);
            assert!(close(&v["max_depth"], want.max_depth), "{v}");
            break;
        }
        assert!(
            std::time::Instant::now() < end,
            "never the meshes' volume: {v}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut bare = s.scene.clone();
    bare.a = innersphere::SharedTree::new(bare.a.tree().clone());
    let err = serve(bare, opts, |_| {}).unwrap_err();
    assert!(err.contains("mesh contact needs both meshes"), "{err}");
}

#[test]
fn the_loop_runs_and_its_state_streams() {
    let (code, info) = json("GET", "/api/info", "");
    assert_eq!(code, 200);
    assert!(info["bodies"]["a"]["leaves"].as_u64().unwrap() > 100);
    std::thread::sleep(Duration::from_millis(600));
    let (code, st) = json("GET", "/api/state", "");
    assert_eq!(code, 200);
    let rate = st["loop"]["rate_hz"].as_f64().unwrap();
    assert!(rate > 500.0 && rate < 1500.0, "loop rate {rate} Hz");
    assert!(st["loop"]["ticks"].as_u64().unwrap() > 300);
    // Modes and motion.
    assert_eq!(json("POST", "/api/mode", r#"{"mode":"haptic"}"#).0, 200);
    assert_eq!(json("POST", "/api/motion", r#"{"t": 1.5}"#).0, 200);
    assert_eq!(json("POST", "/api/mode", r#"{"mode":"free"}"#).0, 200);
    // The event stream sends state lines.
    let mut s = TcpStream::connect(server().addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(s, "GET /api/events HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    let mut buf = vec![0u8; 8192];
    let mut got = Vec::new();
    while !String::from_utf8_lossy(&got).contains("\"loop\"") {
        let n = s.read(&mut buf).unwrap();
        assert!(n > 0, "the stream ended");
        got.extend_from_slice(&buf[..n]);
    }
    assert!(String::from_utf8_lossy(&got).contains("data: {"));
    // Page, assets, binary data.
    let (code, page) = request("GET", "/", "");
    assert_eq!(code, 200);
    assert!(!page.is_empty());
    assert_eq!(
        request("GET", "/assets/vendor/three.module.min.js", "").0,
        200
    );
    let (code, sph) = request("GET", "/api/spheres?body=b&level=3", "");
    assert_eq!(code, 200);
    assert_eq!(sph.len() % 16, 0);
    let (code, mesh) = request("GET", "/api/mesh?body=a", "");
    assert_eq!(code, 200);
    let v = u32::from_le_bytes(mesh[..4].try_into().unwrap()) as usize;
    let t = u32::from_le_bytes(mesh[4..8].try_into().unwrap()) as usize;
    assert_eq!(mesh.len(), 8 + 12 * v + 12 * t);
}

#[test]
fn bad_requests_get_a_4xx_with_a_message() {
    let cases: &[(&str, &str, &str, u16)] = &[
        ("POST", "/api/pose", r#"{"pose_b": [1, 2]}"#, 400),
        (
            "POST",
            "/api/pose",
            r#"{"pose_b": [0, 0, 0, 0, 0, 0, 0]}"#,
            400,
        ),
        (
            "POST",
            "/api/pose",
            r#"{"pose_b": [0, 0, 0, 1, 0, 0, "x"]}"#,
            400,
        ),
        ("POST", "/api/pose", "not json", 400),
        (
            "POST",
            "/api/pose",
            r#"{"pose_b": [1e300, 0, 0, 1, 0, 0, 0]}"#,
            200,
        ),
        ("POST", "/api/mode", r#"{"mode": "dance"}"#, 400),
        ("POST", "/api/motion", r#"{"t": "soon"}"#, 400),
        ("POST", "/api/motion", r#"{}"#, 400),
        ("GET", "/api/spheres?body=c", "", 400),
        ("GET", "/api/spheres?body=a&level=-1", "", 400),
        ("GET", "/api/spheres", "", 400),
        ("GET", "/api/mesh?body=z", "", 400),
        ("GET", "/assets/../../Cargo.toml", "", 404),
        ("GET", "/assets/%2e%2e/Cargo.toml", "", 404),
        ("GET", "/etc/passwd", "", 404),
        ("DELETE", "/api/state", "", 405),
        ("GET", "/api/pose", "", 405),
        ("GET", "/api/nope", "", 404),
        ("POST", "/assets/app.js", "", 404),
    ];
    for (m, p, b, want) in cases {
        let (code, v) = json(m, p, b);
        assert_eq!(code, *want, "{m} {p} {b}: {v}");
        if *want >= 400 {
            assert!(
                v["error"].as_str().is_some_and(|e| !e.is_empty()),
                "{m} {p}: {v}"
            );
        }
    }
    let big = format!("{{\"pose_b\": [{}]}}", "0,".repeat(40_000));
    assert_eq!(request("POST", "/api/pose", &big).0, 413);
    // Still serving.
    assert_eq!(json("GET", "/api/state", "").0, 200);
}

/// The band index the page gets for a gap: the colour scale's own (`gap_colour`), as an
/// index into `LEGEND`, or the far band after it.
fn band_of(gap: f64) -> u8 {
    use innersphere_dental::contact_map::{gap_colour, LEGEND};
    let c = gap_colour(gap);
    LEGEND.iter().position(|l| l.2 == c).unwrap_or(LEGEND.len()) as u8
}

#[test]
fn the_contact_map_is_the_library_s_at_the_map_s_pose() {
    use innersphere::exact::ExactMesh;
    use innersphere_dental::contact_map::ContactMap;
    let s = server();
    let (code, info) = json("GET", "/api/info", "");
    assert_eq!(code, 200);
    assert_eq!(info["contact_map"]["available"], true);
    assert_eq!(info["contact_map"]["legend"].as_array().unwrap().len(), 7);
    let (code, v) = json("POST", "/api/contact-map", r#"{"on": true}"#);
    assert_eq!((code, &v["on"]), (200, &Value::Bool(true)), "{v}");
    // A map arrives (the demo's meshes are prepared first).
    let end = std::time::Instant::now() + Duration::from_secs(60);
    let map = loop {
        let (_, m) = json("GET", "/api/contact-map", "");
        if m["status"] == "ready" && m["seq"].as_u64().unwrap() > 0 {
            break m;
        }
        assert!(std::time::Instant::now() < end, "no map: {m}");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(
        map["pose_b"].as_array().is_some_and(|p| p.len() == 7),
        "{map}"
    );
    // The bands: one per vertex of each mesh, in the mesh's order, the colour scale of the
    // library's gaps at the pose the answer names.
    let (code, bands) = request("GET", "/api/contact-map/bands", "");
    assert_eq!(code, 200);
    let u = |k: usize| u32::from_le_bytes(bands[4 * k..4 * k + 4].try_into().unwrap()) as usize;
    let (ma, mb) = (
        s.scene.mesh_a.as_ref().unwrap(),
        s.scene.mesh_b.as_ref().unwrap(),
    );
    assert_eq!(
        (u(1), u(2), u(3)),
        (ma.vertices.len(), mb.vertices.len(), 7)
    );
    assert_eq!(bands.len(), 72 + u(1) + u(2));
    let mut p7 = [0.0; 7];
    for (k, x) in p7.iter_mut().enumerate() {
        *x = f64::from_le_bytes(bands[16 + 8 * k..24 + 8 * k].try_into().unwrap());
    }
    let pose = Pose::from_array(p7).unwrap();
    let (ea, eb) = (ExactMesh::new(ma).unwrap(), ExactMesh::new(mb).unwrap());
    let exact = ContactMap::new(&ea, &Pose::IDENTITY, &eb, &pose, f64::INFINITY).unwrap();
    let want: Vec<u8> = exact
        .gaps_a
        .iter()
        .chain(&exact.gaps_b)
        .map(|&g| band_of(g))
        .collect();
    assert_eq!(&bands[72..], &want[..], "at {pose}");
    // The state says so too; `after` waits for a map other than the one named.
    let (_, st) = json("GET", "/api/state", "");
    assert_eq!(st["contact_map"]["on"], true);
    let seq = u(0);
    let t0 = std::time::Instant::now();
    let (code, again) = request(
        "GET",
        &format!("/api/contact-map/bands?after={}", seq + 1_000_000),
        "",
    );
    assert_eq!(code, 200);
    assert!(
        t0.elapsed() < Duration::from_secs(1),
        "a newer map than asked for is answered at once"
    );
    assert!(again.len() == bands.len());
    assert_eq!(json("GET", "/api/contact-map/bands?after=x", "").0, 400);
    assert_eq!(json("POST", "/api/contact-map", r#"{"on": "yes"}"#).0, 400);
    assert_eq!(json("POST", "/api/contact-map", r#"{"on": false}"#).0, 200);
}

#[test]
fn a_scene_without_meshes_has_no_contact_map() {
    let mut scene = server().scene.clone();
    scene.mesh_b = None;
    let addr = serve_scene(scene.clone(), ServeOptions::default());
    let get = |path: &str, body: Option<&str>| {
        let mut s = TcpStream::connect(addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        let (m, b) = body.map_or(("GET", ""), |b| ("POST", b));
        write!(
            s,
            "{m} {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\nContent-Length: {}\r\n\r\n{b}",
            b.len()
        )
        .unwrap();
        let mut out = String::new();
        s.read_to_string(&mut out).unwrap();
        out
    };
    assert!(get("/api/info", None).contains("\"available\":false"));
    for (p, b) in [
        ("/api/contact-map", None),
        ("/api/contact-map/bands", None),
        ("/api/contact-map", Some(r#"{"on": true}"#)),
    ] {
        let r = get(p, b);
        assert!(r.starts_with("HTTP/1.1 409"), "{p}: {r}");
        assert!(r.contains("needs both meshes"), "{r}");
    }
    assert!(get("/api/state", None).contains("\"contact_map\":null"));
    // Starting in the mode is refused without both meshes.
    let opts = ServeOptions {
        port: 0,
        contact_map: true,
        ..Default::default()
    };
    assert!(serve(scene, opts, |_| {})
        .unwrap_err()
        .contains("needs both meshes"));
}

#[test]
fn a_splint_is_served_in_a_s_frame_and_b_starts_at_its_pose() {
    // The demo scene has no splint: the info says so and the mesh is a 404.
    let (code, info) = json("GET", "/api/info", "");
    assert_eq!((code, &info["splint"]), (200, &Value::Bool(false)));
    assert_eq!(request("GET", "/api/mesh?body=splint", "").0, 404);
    // A scene with one (a small box standing in for it) and B's start pose.
    let mut scene = server().scene.clone();
    let splint = innersphere::shapes::cuboid(innersphere::glam::DVec3::new(1.0, 0.5, 0.25));
    scene.splint = Some(splint.clone());
    let start = innersphere::Pose::from_translation(innersphere::glam::DVec3::new(0.0, 0.0, -0.5));
    scene.start = Some(start);
    scene.motion = None; // in motion mode the motion moves B
    let addr = serve_scene(scene, ServeOptions::default());
    let get = |path: &str| -> Vec<u8> {
        let (code, body) = request_to(addr, "GET", path, "");
        assert_eq!(code, 200, "{path}");
        body
    };
    let info: Value = serde_json::from_slice(&get("/api/info")).unwrap();
    assert_eq!(info["splint"], true);
    let mesh = get("/api/mesh?body=splint");
    let nv = u32::from_le_bytes(mesh[0..4].try_into().unwrap()) as usize;
    let nt = u32::from_le_bytes(mesh[4..8].try_into().unwrap()) as usize;
    assert_eq!((nv, nt), (splint.vertices.len(), splint.triangles.len()));
    assert_eq!(mesh.len(), 8 + 12 * nv + 12 * nt);
    let state: Value = serde_json::from_slice(&get("/api/state")).unwrap();
    let t = &state["target_b"];
    assert!(close(&t[2], -0.5) && close(&t[0], 0.0), "{state}");
}
