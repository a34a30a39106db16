//! The HTTP side: the page, its files, and the JSON/binary API (`docs/VIEWER.md`), on
//! 127.0.0.1 only. Requests are matched against a fixed table: nothing names a file, bodies
//! are capped, and every bad request gets a 4xx with a message.

use crate::sim::{self, Control, LoopIo, LoopState, Mode};
use crate::{assets, encode, Scene};
use innersphere::{DistanceOptions, Pair, PenetrationOptions, Pose};
use serde_json::{json, Value};
use std::io::{Cursor, Read};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tiny_http::{Header, Method, Request, Response, Server, StatusCode};

/// Largest request body read (bytes).
const MAX_BODY: u64 = 64 * 1024;
/// Server-sent-event streams open at once.
const MAX_STREAMS: usize = 16;
/// Worker threads answering requests.
const WORKERS: usize = 4;

/// Settings of [`serve`].
#[derive(Debug, Clone, Copy)]
pub struct ServeOptions {
    /// Port on 127.0.0.1 (0: any free one).
    pub port: u16,
    /// Penalty stiffness of the penetration answers (force per unit volume; 1 = `ist query`'s).
    pub stiffness: f64,
    /// Loop ticks per second.
    pub rate: f64,
}

impl Default for ServeOptions {
    fn default() -> Self {
        ServeOptions {
            port: 8000,
            stiffness: 1.0,
            rate: 1000.0,
        }
    }
}

/// Everything the request handlers share.
struct App {
    scene: Scene,
    opts: ServeOptions,
    /// The HTTP side's end of the control buffer (the loop reads the other end lock-free).
    control: Mutex<(triple_buffer::Input<Control>, Control)>,
    /// The HTTP side's end of the state buffer.
    state: Mutex<triple_buffer::Output<LoopState>>,
    streams: AtomicUsize,
    stop: Arc<AtomicBool>,
}

type Resp = Response<Cursor<Vec<u8>>>;

fn header(name: &str, value: &str) -> Header {
    Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("ASCII header")
}

fn json_response(code: u16, v: &Value) -> Resp {
    Response::from_data(serde_json::to_vec(v).unwrap_or_default())
        .with_status_code(StatusCode(code))
        .with_header(header("Content-Type", "application/json"))
        .with_header(header("Cache-Control", "no-store"))
}

fn error(code: u16, message: impl Into<String>) -> Resp {
    json_response(code, &json!({"error": message.into()}))
}

fn binary(bytes: Vec<u8>) -> Resp {
    Response::from_data(bytes)
        .with_header(header("Content-Type", "application/octet-stream"))
        .with_header(header("Cache-Control", "no-store"))
}

/// Serves `scene` until the process ends: starts the loop thread and the HTTP workers, calls
/// `listening` with the address once the socket is bound, then blocks.
pub fn serve(
    scene: Scene,
    opts: ServeOptions,
    listening: impl FnOnce(SocketAddr),
) -> Result<(), String> {
    if !(opts.rate.is_finite() && (1.0..=20_000.0).contains(&opts.rate)) {
        return Err(format!(
            "the loop rate must be 1 to 20000 Hz, not {}",
            opts.rate
        ));
    }
    if !(opts.stiffness.is_finite() && opts.stiffness >= 0.0) {
        return Err(format!(
            "the stiffness must be finite and not negative, not {}",
            opts.stiffness
        ));
    }
    let server = Server::http(("127.0.0.1", opts.port))
        .map_err(|e| format!("cannot listen on 127.0.0.1:{}: {e}", opts.port))?;
    let addr = server
        .server_addr()
        .to_ip()
        .ok_or("the server has no IP address")?;
    // B starts where the motion starts, else beside A, apart along x.
    let start = match &scene.motion {
        Some(m) if !m.frames.is_empty() => m.frames[0].pose,
        _ => {
            let (a, b) = (&scene.a, &scene.b);
            let wa = a.meta.bbox_max[0] - a.meta.bbox_min[0];
            let wb = b.meta.bbox_max[0] - b.meta.bbox_min[0];
            Pose::from_translation(innersphere::glam::DVec3::new(0.6 * (wa + wb), 0.0, 0.0))
        }
    };
    let control0 = Control {
        target: start,
        mode: if scene.motion.is_some() {
            Mode::Motion
        } else {
            Mode::Free
        },
        playing: false,
        seek: 0.0,
        seek_id: 0,
    };
    let (control_in, control_out) = triple_buffer::triple_buffer(&control0);
    let (state_in, state_out) = triple_buffer::triple_buffer(&LoopState::initial(start));
    let stop = Arc::new(AtomicBool::new(false));
    let io = LoopIo {
        control: control_out,
        state: state_in,
        stop: stop.clone(),
    };
    {
        let (a, b, m) = (scene.a.clone(), scene.b.clone(), scene.motion.clone());
        let (k, rate) = (opts.stiffness, opts.rate);
        std::thread::Builder::new()
            .name("ist-view-loop".into())
            .spawn(move || sim::run(a, b, m, k, rate, io))
            .map_err(|e| format!("cannot start the loop thread: {e}"))?;
    }
    let app = Arc::new(App {
        scene,
        opts,
        control: Mutex::new((control_in, control0)),
        state: Mutex::new(state_out),
        streams: AtomicUsize::new(0),
        stop,
    });
    listening(addr);
    let server = Arc::new(server);
    let workers: Vec<_> = (0..WORKERS)
        .map(|_| {
            let (server, app) = (server.clone(), app.clone());
            std::thread::spawn(move || {
                while let Ok(req) = server.recv() {
                    handle(&app, req);
                }
            })
        })
        .collect();
    for w in workers {
        let _ = w.join();
    }
    app.stop.store(true, Ordering::Relaxed);
    Ok(())
}

fn handle(app: &Arc<App>, mut req: Request) {
    let url = req.url().to_string();
    let (path, query) = url.split_once('?').unwrap_or((&url, ""));
    let method = req.method().clone();
    if method == Method::Get && path == "/api/events" {
        return events(app, req);
    }
    let resp = match (&method, path) {
        (Method::Get, "/") | (Method::Get, "/index.html") => asset("index.html"),
        (Method::Get, p) if p.starts_with("/assets/") => asset(&p["/assets/".len()..]),
        (Method::Get, "/api/info") => json_response(200, &info(app)),
        (Method::Get, "/api/state") => json_response(200, &state_json(app)),
        (Method::Get, "/api/spheres") => spheres(app, query),
        (Method::Get, "/api/mesh") => mesh(app, query),
        (Method::Post, "/api/pose") => match body(&mut req) {
            Ok(v) => pose(app, &v),
            Err(r) => r,
        },
        (Method::Post, "/api/mode") => match body(&mut req) {
            Ok(v) => mode(app, &v),
            Err(r) => r,
        },
        (Method::Post, "/api/motion") => match body(&mut req) {
            Ok(v) => motion(app, &v),
            Err(r) => r,
        },
        (_, "/" | "/index.html" | "/api/info" | "/api/state" | "/api/spheres" | "/api/mesh")
        | (_, "/api/pose" | "/api/mode" | "/api/motion" | "/api/events") => {
            error(405, format!("{method} is not allowed on {path}"))
        }
        (_, p) => error(404, format!("nothing at {p}")),
    };
    let _ = req.respond(resp);
}

fn asset(path: &str) -> Resp {
    match assets::get(path) {
        Some((ty, bytes)) => {
            Response::from_data(bytes.to_vec()).with_header(header("Content-Type", ty))
        }
        None => error(404, format!("no asset {path}")),
    }
}

/// The request's JSON body, at most [`MAX_BODY`] bytes.
fn body(req: &mut Request) -> Result<Value, Resp> {
    if req.body_length().is_some_and(|n| n as u64 > MAX_BODY) {
        return Err(error(413, format!("the body is over {MAX_BODY} bytes")));
    }
    let mut buf = Vec::new();
    req.as_reader()
        .take(MAX_BODY + 1)
        .read_to_end(&mut buf)
        .map_err(|e| error(400, format!("reading the body: {e}")))?;
    if buf.len() as u64 > MAX_BODY {
        return Err(error(413, format!("the body is over {MAX_BODY} bytes")));
    }
    serde_json::from_slice(&buf).map_err(|e| error(400, format!("the body is not JSON: {e}")))
}

fn latest(app: &App) -> LoopState {
    let mut out = app.state.lock().unwrap_or_else(|e| e.into_inner());
    *out.read()
}

fn motion_seconds(app: &App) -> Option<f64> {
    app.scene.motion.as_ref().map(|m| m.duration())
}

fn state_json(app: &App) -> Value {
    encode::state(&latest(app), motion_seconds(app))
}

fn info(app: &App) -> Value {
    let body = |t: &innersphere::SphereTree, mesh: bool| {
        json!({
            "leaves": t.leaf_count(),
            "depth": t.max_depth(),
            "levels": t.max_depth() as usize + 1,
            "bbox_min": t.meta.bbox_min,
            "bbox_max": t.meta.bbox_max,
            "has_mesh": mesh,
        })
    };
    let s = &app.scene;
    let mut modes = vec!["free"];
    if s.b.meta.inertia.is_some() {
        modes.push("haptic");
    }
    if s.motion.is_some() {
        modes.push("motion");
    }
    json!({
        "bodies": {"a": body(&s.a, s.mesh_a.is_some()), "b": body(&s.b, s.mesh_b.is_some())},
        "motion": s.motion.as_ref().map(|m| json!({"frames": m.len(), "seconds": m.duration()})),
        "rate_hz": app.opts.rate,
        "modes": modes,
        "stiffness": app.opts.stiffness,
    })
}

/// `body=a|b` from the query string.
fn which<'a>(
    app: &'a App,
    query: &str,
) -> Result<(&'a innersphere::SphereTree, Option<&'a innersphere::Mesh>), Resp> {
    match param(query, "body") {
        Some("a") => Ok((&app.scene.a, app.scene.mesh_a.as_ref())),
        Some("b") => Ok((&app.scene.b, app.scene.mesh_b.as_ref())),
        Some(x) => Err(error(400, format!("body must be a or b, not {x}"))),
        None => Err(error(400, "missing body=a|b")),
    }
}

fn param<'a>(query: &'a str, name: &str) -> Option<&'a str> {
    query
        .split('&')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == name)
        .map(|(_, v)| v)
}

fn spheres(app: &App, query: &str) -> Resp {
    let (tree, _) = match which(app, query) {
        Ok(t) => t,
        Err(r) => return r,
    };
    let level = match param(query, "level").map(str::parse::<usize>) {
        Some(Ok(l)) if l <= u16::MAX as usize => l,
        Some(_) => return error(400, "level must be a whole number ≥ 0"),
        None => tree.max_depth() as usize,
    };
    binary(encode::spheres(tree, level))
}

fn mesh(app: &App, query: &str) -> Resp {
    match which(app, query) {
        Ok((_, Some(m))) => binary(encode::mesh(m)),
        Ok((_, None)) => error(
            404,
            "this body has no mesh (start ist view with --mesh-a/--mesh-b)",
        ),
        Err(r) => r,
    }
}

/// A pose from a JSON array of 7 finite numbers.
fn pose_of(v: Option<&Value>) -> Result<Pose, String> {
    let arr = v
        .and_then(|v| v.as_array())
        .ok_or("expected \"pose_b\": [tx, ty, tz, qw, qx, qy, qz]")?;
    if arr.len() != 7 {
        return Err(format!("a pose has 7 numbers, not {}", arr.len()));
    }
    let mut x = [0.0; 7];
    for (o, v) in x.iter_mut().zip(arr) {
        *o = v.as_f64().ok_or("the pose's entries must be numbers")?;
    }
    Pose::from_array(x).map_err(|e| format!("not a pose: {e}"))
}

fn set_control(app: &App, f: impl FnOnce(&mut Control)) -> Control {
    let mut g = app.control.lock().unwrap_or_else(|e| e.into_inner());
    let (input, current) = &mut *g;
    f(current);
    input.write(*current);
    *current
}

/// Sets B's target and answers the queries at that pose as `ist query --json` would (a fresh
/// pair, so that the answer depends on the pose alone).
fn pose(app: &App, v: &Value) -> Resp {
    let p = match pose_of(v.get("pose_b")) {
        Ok(p) => p,
        Err(e) => return error(400, e),
    };
    set_control(app, |c| c.target = p);
    let mut pair = Pair::new(app.scene.a.clone(), app.scene.b.clone());
    let id = Pose::IDENTITY;
    let d = pair.distance_with(
        &id,
        &p,
        &DistanceOptions {
            coherence: false,
            ..Default::default()
        },
    );
    let q = pair.penetration_with(
        &id,
        &p,
        &PenetrationOptions {
            stiffness: app.opts.stiffness,
            safe_motion: false,
            ..Default::default()
        },
    );
    json_response(
        200,
        &json!({
            "pose_b": p.to_array(),
            "distance": d.distance,
            "contact": d.overlapping,
            "point_a": d.point_a.to_array(),
            "point_b": d.point_b.to_array(),
            "volume": q.volume,
            "pairs": q.pairs,
            "max_depth": q.max_depth,
            "normal": q.normal.to_array(),
            "force": q.force.to_array(),
            "torque": q.torque_b.to_array(),
            "patches": pair.patches().iter().map(encode::patch).collect::<Vec<_>>(),
        }),
    )
}

fn mode(app: &App, v: &Value) -> Resp {
    let m = match v.get("mode").and_then(|m| m.as_str()) {
        Some("free") => Mode::Free,
        Some("haptic") if app.scene.b.meta.inertia.is_some() => Mode::Haptic,
        Some("haptic") => {
            return error(
                409,
                "haptic mode needs B's tree to hold mass properties: rebuild it with ist build",
            )
        }
        Some("motion") if app.scene.motion.is_some() => Mode::Motion,
        Some("motion") => return error(409, "no motion was given (--motion M.csv)"),
        _ => {
            return error(
                400,
                "expected {\"mode\": \"free\" | \"haptic\" | \"motion\"}",
            )
        }
    };
    let c = set_control(app, |c| c.mode = m);
    json_response(200, &json!({"mode": c.mode.name()}))
}

fn motion(app: &App, v: &Value) -> Resp {
    let Some(len) = motion_seconds(app) else {
        return error(409, "no motion was given (--motion M.csv)");
    };
    let playing = match v.get("playing") {
        None => None,
        Some(Value::Bool(b)) => Some(*b),
        Some(_) => return error(400, "playing must be true or false"),
    };
    let t = match v.get("t") {
        None => None,
        Some(x) => match x.as_f64() {
            Some(t) if t.is_finite() => Some(t.clamp(0.0, len)),
            _ => return error(400, "t must be a finite number of seconds"),
        },
    };
    if playing.is_none() && t.is_none() {
        return error(400, "expected {\"playing\": bool} and/or {\"t\": seconds}");
    }
    let c = set_control(app, |c| {
        if let Some(p) = playing {
            c.playing = p;
        }
        if let Some(t) = t {
            c.seek = t;
            c.seek_id += 1;
        }
        if playing == Some(true) {
            c.mode = Mode::Motion;
        }
    });
    json_response(
        200,
        &json!({"playing": c.playing, "t": t.unwrap_or(latest(app).motion_t), "seconds": len}),
    )
}

/// Server-sent events: the state about 30 times a second, in a thread of its own.
fn events(app: &Arc<App>, req: Request) {
    if app.streams.fetch_add(1, Ordering::SeqCst) >= MAX_STREAMS {
        app.streams.fetch_sub(1, Ordering::SeqCst);
        let _ = req.respond(error(
            503,
            format!("at most {MAX_STREAMS} event streams at once"),
        ));
        return;
    }
    let app = app.clone();
    std::thread::spawn(move || {
        let stream = Events {
            app: app.clone(),
            buf: Vec::new(),
            pos: 0,
        };
        let resp = Response::new(
            StatusCode(200),
            vec![
                header("Content-Type", "text/event-stream"),
                header("Cache-Control", "no-store"),
            ],
            stream,
            None,
            None,
        );
        let _ = req.respond(resp);
        app.streams.fetch_sub(1, Ordering::SeqCst);
    });
}

/// An endless body: one `data:` line of state JSON every 33 ms.
struct Events {
    app: Arc<App>,
    buf: Vec<u8>,
    pos: usize,
}

impl Read for Events {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if self.pos >= self.buf.len() {
            if self.app.stop.load(Ordering::Relaxed) {
                return Ok(0);
            }
            std::thread::sleep(Duration::from_millis(33));
            self.buf.clear();
            self.buf.extend_from_slice(b"data: ");
            serde_json::to_writer(&mut self.buf, &state_json(&self.app))?;
            self.buf.extend_from_slice(b"\n\n");
            self.pos = 0;
        }
        let n = out.len().min(self.buf.len() - self.pos);
        out[..n].copy_from_slice(&self.buf[self.pos..n + self.pos]);
        self.pos += n;
        Ok(n)
    }
}
