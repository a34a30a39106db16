//! The HTTP side: the page, its files, and the JSON/binary API (`docs/VIEWER.md`), on
//! 127.0.0.1 only, served by hyper on a small tokio runtime. Requests are matched against a
//! fixed table: nothing names a file, and every bad request gets a 4xx with a message. What a
//! hostile or broken client can do is bounded: a request's headers must arrive within
//! [`HEADER_TIMEOUT`] and fit [`MAX_HEADER`] (else 431), a body within [`BODY_TIMEOUT`] and
//! [`MAX_BODY`] (else 408 or 413), a response must be taken within [`WRITE_TIMEOUT`], and at
//! most [`ServeOptions::max_connections`] connections are open (the next is told 503 and
//! closed). Each connection is a task of its own: a slow one holds up nobody else.

// A handler's error is the response it answers with, made once per request.
#![allow(clippy::result_large_err)]

use crate::contact::{self, ContactMaps};
use crate::sim::{self, Control, LoopIo, LoopState, Mode};
use crate::{assets, encode, Scene};
use bytes::Bytes;
use http_body_util::{combinators::BoxBody, BodyExt, Full, Limited, StreamBody};
use hyper::body::{Frame, Incoming};
use hyper::header::{HeaderValue, CACHE_CONTROL, CONTENT_LENGTH, CONTENT_TYPE};
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use innersphere::{DistanceOptions, Pair, PenetrationOptions, Pose};
use innersphere_haptic::ContactSource;
use serde_json::{json, Value};
use std::convert::Infallible;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::AsyncWriteExt;
use tokio::sync::Semaphore;

/// Largest request body read (bytes).
pub const MAX_BODY: u64 = 64 * 1024;
/// Largest request head (request line and headers) read (bytes).
pub const MAX_HEADER: usize = 16 * 1024;
/// Time a client has to send a request's head once it starts, or between requests on a
/// kept-alive connection.
pub const HEADER_TIMEOUT: Duration = Duration::from_secs(5);
/// Time a client has to send a request's body.
pub const BODY_TIMEOUT: Duration = Duration::from_secs(5);
/// Time a write to a client may stall (a client that sends and never reads).
pub const WRITE_TIMEOUT: Duration = Duration::from_secs(10);
/// Connections open at once by default ([`ServeOptions::max_connections`]).
pub const MAX_CONNECTIONS: usize = 512;
/// Server-sent-event streams open at once.
const MAX_STREAMS: usize = 16;
/// Longest wait of `GET /api/contact-map/bands?after=SEQ` for a newer map.
const MAP_WAIT: Duration = Duration::from_secs(2);

/// Settings of [`serve`].
#[derive(Debug, Clone, Copy)]
pub struct ServeOptions {
    /// Port on 127.0.0.1 (0: any free one).
    pub port: u16,
    /// Penalty stiffness of the penetration answers (force per unit volume; 1 = `ist query`'s).
    pub stiffness: f64,
    /// Loop ticks per second.
    pub rate: f64,
    /// Connections open at once; the next is told 503 and closed.
    pub max_connections: usize,
    /// Time a client has for a request's head, and between requests on a kept-alive
    /// connection ([`HEADER_TIMEOUT`] by default).
    pub header_timeout: Duration,
    /// Time a client has for a request's body ([`BODY_TIMEOUT`] by default).
    pub body_timeout: Duration,
    /// Start with the contact map on (both meshes needed).
    pub contact_map: bool,
    /// Where the readout's and the haptic mode's contact comes from: the sphere packings'
    /// volume, or the meshes' own (the trees must carry their meshes).
    pub contact: ContactSource,
}

impl Default for ServeOptions {
    fn default() -> Self {
        ServeOptions {
            port: 8000,
            stiffness: 1.0,
            rate: 1000.0,
            max_connections: MAX_CONNECTIONS,
            header_timeout: HEADER_TIMEOUT,
            body_timeout: BODY_TIMEOUT,
            contact_map: false,
            contact: ContactSource::Spheres,
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
    /// The contact map's shared state, where both meshes are given.
    maps: Option<Arc<ContactMaps>>,
}

type Body = BoxBody<Bytes, Infallible>;
type Resp = Response<Body>;

fn respond(code: u16, content_type: &'static str, bytes: Vec<u8>) -> Resp {
    let mut r = Response::new(Full::new(Bytes::from(bytes)).boxed());
    *r.status_mut() = StatusCode::from_u16(code).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
    r.headers_mut()
        .insert(CONTENT_TYPE, HeaderValue::from_static(content_type));
    r
}

fn no_store(mut r: Resp) -> Resp {
    r.headers_mut()
        .insert(CACHE_CONTROL, HeaderValue::from_static("no-store"));
    r
}

fn json_response(code: u16, v: &Value) -> Resp {
    no_store(respond(
        code,
        "application/json",
        serde_json::to_vec(v).unwrap_or_default(),
    ))
}

fn error(code: u16, message: impl Into<String>) -> Resp {
    json_response(code, &json!({"error": message.into()}))
}

fn binary(bytes: Vec<u8>) -> Resp {
    no_store(respond(200, "application/octet-stream", bytes))
}

/// Shared bytes (a published contact map), answered without a copy.
fn binary_shared(bytes: Bytes) -> Resp {
    let mut r = Response::new(Full::new(bytes).boxed());
    r.headers_mut().insert(
        CONTENT_TYPE,
        HeaderValue::from_static("application/octet-stream"),
    );
    no_store(r)
}

/// Serves `scene` until the process ends: starts the loop thread and the server, calls
/// `listening` with the address once the socket is bound, then blocks.
pub fn serve(
    scene: Scene,
    opts: ServeOptions,
    listening: impl FnOnce(SocketAddr),
) -> Result<(), String> {
    if !(opts.rate.is_finite() && (1.0..=20_000.0).contains(&opts.rate)) {
        return Err(format!(
            "the loop rate must be 1 to 20000 Hz, not {}",
            innersphere::error::num(opts.rate)
        ));
    }
    if opts.header_timeout.is_zero() || opts.body_timeout.is_zero() {
        return Err("the header and body timeouts must be above zero".into());
    }
    let meshes = scene.mesh_a.is_some() && scene.mesh_b.is_some();
    if opts.contact_map && !meshes {
        return Err("the contact map needs both meshes (--mesh-a and --mesh-b)".into());
    }
    if opts.contact == ContactSource::Mesh && (scene.a.mesh().is_none() || scene.b.mesh().is_none())
    {
        return Err(
            "mesh contact needs both meshes, the trees' own (--mesh-a and --mesh-b)".into(),
        );
    }
    if opts.max_connections == 0 {
        return Err("the server must take at least one connection".into());
    }
    if !(opts.stiffness.is_finite() && opts.stiffness >= 0.0) {
        return Err(format!(
            "the stiffness must be finite and not negative, not {}",
            innersphere::error::num(opts.stiffness)
        ));
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("ist-view-http")
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the server's runtime: {e}"))?;
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind(("127.0.0.1", opts.port)))
        .map_err(|e| format!("cannot listen on 127.0.0.1:{}: {e}", opts.port))?;
    let addr = listener
        .local_addr()
        .map_err(|e| format!("the server has no address: {e}"))?;
    // B starts at the given pose, else where the motion starts, else beside A, apart along x.
    let start = match (&scene.start, &scene.motion) {
        (Some(p), _) => *p,
        (None, Some(m)) if !m.frames.is_empty() => m.frames[0].pose,
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
        let (k, rate, contact) = (opts.stiffness, opts.rate, opts.contact);
        std::thread::Builder::new()
            .name("ist-view-loop".into())
            .spawn(move || sim::run(a, b, m, k, rate, contact, io))
            .map_err(|e| format!("cannot start the loop thread: {e}"))?;
    }
    let app = Arc::new(App {
        scene,
        opts,
        control: Mutex::new((control_in, control0)),
        state: Mutex::new(state_out),
        streams: AtomicUsize::new(0),
        stop,
        maps: meshes.then(|| Arc::new(ContactMaps::new(opts.contact_map))),
    });
    if let Some(maps) = &app.maps {
        // The contact map's worker: B's pose from the HTTP side's end of the state buffer
        // (the loop never waits for it), the meshes borrowed from the scene.
        let (app, maps) = (app.clone(), maps.clone());
        std::thread::Builder::new()
            .name("ist-view-contact-map".into())
            .spawn(move || {
                let s = &app.scene;
                if let (Some(mesh_a), Some(mesh_b)) = (&s.mesh_a, &s.mesh_b) {
                    let src = contact::Source {
                        mesh_a,
                        mesh_b,
                        teeth_a: s.teeth_a.as_ref(),
                        teeth_b: s.teeth_b.as_ref(),
                    };
                    contact::run(src, &maps, || latest(&app).pose_b, &app.stop);
                }
            })
            .map_err(|e| format!("cannot start the contact map's thread: {e}"))?;
    }
    listening(addr);
    let result = runtime.block_on(accept(listener, app.clone()));
    app.stop.store(true, Ordering::Relaxed);
    result
}

/// Accepts connections until the listener fails, each served by a task of its own.
async fn accept(listener: tokio::net::TcpListener, app: Arc<App>) -> Result<(), String> {
    let cap = app.opts.max_connections;
    let slots = Arc::new(Semaphore::new(cap));
    loop {
        let (socket, _) = match listener.accept().await {
            Ok(c) => c,
            // Out of file descriptors and the like: wait a moment, go on.
            Err(_) => {
                tokio::time::sleep(Duration::from_millis(10)).await;
                continue;
            }
        };
        let _ = socket.set_nodelay(true);
        let Ok(slot) = slots.clone().try_acquire_owned() else {
            tokio::spawn(refuse(socket, cap));
            continue;
        };
        let app = app.clone();
        let header_timeout = app.opts.header_timeout;
        tokio::spawn(async move {
            let mut stream = tokio_io_timeout::TimeoutStream::new(socket);
            stream.set_write_timeout(Some(WRITE_TIMEOUT));
            let io = TokioIo::new(Box::pin(stream));
            let service = hyper::service::service_fn(move |req| {
                let app = app.clone();
                async move { Ok::<_, Infallible>(handle(app, req).await) }
            });
            let _ = hyper::server::conn::http1::Builder::new()
                .timer(TokioTimer::new())
                .header_read_timeout(header_timeout)
                .max_buf_size(MAX_HEADER.max(8192))
                .serve_connection(io, service)
                .await;
            drop(slot);
        });
    }
}

/// Tells a connection over the cap so, and closes it.
async fn refuse(mut socket: tokio::net::TcpStream, cap: usize) {
    let body = format!("{{\"error\":\"the viewer has {cap} connections open; try again\"}}");
    let text = format!(
        "HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    let _ = tokio::time::timeout(WRITE_TIMEOUT, socket.write_all(text.as_bytes())).await;
    let _ = socket.shutdown().await;
}

async fn handle(app: Arc<App>, req: Request<Incoming>) -> Resp {
    let method = req.method().clone();
    let path = req.uri().path().to_string();
    let query = req.uri().query().unwrap_or("").to_string();
    // HEAD is GET without the body (hyper leaves the body out).
    let get = method == Method::GET || method == Method::HEAD;
    if get && path == "/api/events" {
        return events(&app);
    }
    // A page that shows map `after` asks for the next one: wait for it here (a task, no
    // thread), at most MAP_WAIT, then answer the latest.
    if get && path == "/api/contact-map/bands" {
        if let (Some(maps), Some(after)) = (&app.maps, param(&query, "after")) {
            let Ok(after) = after.parse::<u32>() else {
                return error(400, "after must be a map's seq (a whole number ≥ 0)");
            };
            let mut seq = maps.subscribe();
            let _ = tokio::time::timeout(MAP_WAIT, seq.wait_for(|s| *s != after)).await;
        }
    }
    let body = if method == Method::POST && path.starts_with("/api/") {
        match read_body(req, app.opts.body_timeout).await {
            Ok(v) => Some(v),
            Err(r) => return r,
        }
    } else {
        None
    };
    // The answers are computed off the runtime's threads: a query or a large encoding does
    // not hold up other connections.
    tokio::task::spawn_blocking(move || route(&app, &method, get, &path, &query, body))
        .await
        .unwrap_or_else(|_| error(500, "the request's handler failed"))
}

fn route(
    app: &App,
    method: &Method,
    get: bool,
    path: &str,
    query: &str,
    body: Option<Value>,
) -> Resp {
    match (get, method, path) {
        (true, _, "/" | "/index.html") => asset("index.html"),
        (true, _, p) if p.starts_with("/assets/") => asset(&p["/assets/".len()..]),
        (true, _, "/api/info") => json_response(200, &info(app)),
        (true, _, "/api/state") => json_response(200, &state_json(app)),
        (true, _, "/api/spheres") => spheres(app, query),
        (true, _, "/api/mesh") => mesh(app, query),
        (true, _, "/api/contact-map") => contact_map(app),
        (true, _, "/api/contact-map/bands") => contact_bands(app),
        (_, &Method::POST, "/api/pose") => pose(app, body.as_ref().unwrap_or(&Value::Null)),
        (_, &Method::POST, "/api/mode") => mode(app, body.as_ref().unwrap_or(&Value::Null)),
        (_, &Method::POST, "/api/motion") => motion(app, body.as_ref().unwrap_or(&Value::Null)),
        (_, &Method::POST, "/api/contact-map") => {
            contact_switch(app, body.as_ref().unwrap_or(&Value::Null))
        }
        (_, _, "/" | "/index.html" | "/api/info" | "/api/state" | "/api/spheres" | "/api/mesh")
        | (_, _, "/api/pose" | "/api/mode" | "/api/motion" | "/api/events")
        | (_, _, "/api/contact-map" | "/api/contact-map/bands") => {
            error(405, format!("{method} is not allowed on {path}"))
        }
        (_, _, p) => error(404, format!("nothing at {p}")),
    }
}

fn asset(path: &str) -> Resp {
    match assets::get(path) {
        Some((ty, bytes)) => respond(200, ty, bytes.to_vec()),
        None => error(404, format!("no asset {path}")),
    }
}

/// The request's JSON body: at most [`MAX_BODY`] bytes (else 413), within `timeout` (else
/// 408).
async fn read_body(req: Request<Incoming>, timeout: Duration) -> Result<Value, Resp> {
    let declared = req
        .headers()
        .get(CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<u64>().ok());
    if declared.is_some_and(|n| n > MAX_BODY) {
        return Err(error(413, format!("the body is over {MAX_BODY} bytes")));
    }
    let limited = Limited::new(req.into_body(), MAX_BODY as usize);
    let bytes = match tokio::time::timeout(timeout, limited.collect()).await {
        Err(_) => {
            return Err(error(
                408,
                format!("the body did not arrive within {} s", timeout.as_secs_f64()),
            ))
        }
        Ok(Err(e)) if e.is::<http_body_util::LengthLimitError>() => {
            return Err(error(413, format!("the body is over {MAX_BODY} bytes")))
        }
        Ok(Err(e)) => return Err(error(400, format!("reading the body: {e}"))),
        Ok(Ok(c)) => c.to_bytes(),
    };
    serde_json::from_slice(&bytes).map_err(|e| error(400, format!("the body is not JSON: {e}")))
}

fn latest(app: &App) -> LoopState {
    let mut out = app.state.lock().unwrap_or_else(|e| e.into_inner());
    *out.read()
}

fn motion_seconds(app: &App) -> Option<f64> {
    app.scene.motion.as_ref().map(|m| m.duration())
}

fn state_json(app: &App) -> Value {
    let mut v = encode::state(&latest(app), motion_seconds(app));
    v["contact_map"] = app
        .maps
        .as_ref()
        .map_or(Value::Null, |m| encode::contact_map(&m.snapshot(), false));
    v
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
        "splint": s.splint.is_some(),
        "motion": s.motion.as_ref().map(|m| json!({"frames": m.len(), "seconds": m.duration()})),
        "rate_hz": app.opts.rate,
        "modes": modes,
        "stiffness": app.opts.stiffness,
        "contact_map": {
            "available": app.maps.is_some(),
            "cap": contact::CAP,
            "legend": encode::contact_legend(),
            "teeth": {"a": s.teeth_a.is_some(), "b": s.teeth_b.is_some()},
        },
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
    if param(query, "body") == Some("splint") {
        return match &app.scene.splint {
            Some(m) => binary(encode::mesh(m)),
            None => error(404, "no splint (start ist view with --splint)"),
        };
    }
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
    // A pair of its own, so that the refined answer too is a fresh pair's (`ist query`'s).
    let r = crate::sim::refined(&mut Pair::new(app.scene.a.clone(), app.scene.b.clone()), &p);
    let mut penetration = serde_json::to_value(q).expect("answers serialize");
    penetration["patches"] = json!(pair.patches());
    // The meshes' own penetration, a fresh pair's too, where the trees carry their meshes.
    let mut meshes = Pair::new(app.scene.a.clone(), app.scene.b.clone());
    let mesh_penetration = meshes
        .mesh_penetration_with(
            &id,
            &p,
            &PenetrationOptions {
                stiffness: app.opts.stiffness,
                ..Default::default()
            },
        )
        .ok()
        .map(|m| {
            let mut v = serde_json::to_value(m).expect("answers serialize");
            v["patches"] = json!(meshes.patches());
            v
        });
    json_response(
        200,
        &json!({
            "pose_b": p.to_array(),
            // Each answer in its serde form, as `ist query --json` prints it: the sphere
            // distance, the penetration with its patches, and the refined distance and the
            // meshes' penetration with its patches where the trees carry their meshes (else
            // null).
            "distance": d,
            "penetration": penetration,
            "refined_distance": r,
            "mesh_penetration": mesh_penetration,
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

/// The contact map's shared state, or the 409 of a scene without both meshes.
fn maps(app: &App) -> Result<&ContactMaps, Resp> {
    app.maps.as_deref().ok_or_else(|| {
        error(
            409,
            "the contact map needs both meshes (start ist view with --mesh-a and --mesh-b)",
        )
    })
}

/// `GET /api/contact-map`: the mode, the latest map's pose, timings and per-tooth summaries.
fn contact_map(app: &App) -> Resp {
    match maps(app) {
        Ok(m) => json_response(200, &encode::contact_map(&m.snapshot(), true)),
        Err(r) => r,
    }
}

/// `GET /api/contact-map/bands[?after=SEQ]`: the latest map, one band index per vertex
/// (binary); with `after`, once there is a map other than SEQ or 2 s have passed.
fn contact_bands(app: &App) -> Resp {
    let m = match maps(app) {
        Ok(m) => m,
        Err(r) => return r,
    };
    match m.snapshot().frame {
        Some(f) => binary_shared(f.bands.clone()),
        None => error(
            404,
            "no contact map yet (turn it on: POST /api/contact-map {\"on\": true})",
        ),
    }
}

/// `POST /api/contact-map {"on": bool}`: turns the mode on or off.
fn contact_switch(app: &App, v: &Value) -> Resp {
    let m = match maps(app) {
        Ok(m) => m,
        Err(r) => return r,
    };
    match v.get("on") {
        Some(Value::Bool(on)) => {
            m.set_on(*on);
            json_response(200, &encode::contact_map(&m.snapshot(), false))
        }
        _ => error(400, "expected {\"on\": true | false}"),
    }
}

/// Server-sent events: the state about 30 times a second, as a stream of its own.
fn events(app: &Arc<App>) -> Resp {
    if app.streams.fetch_add(1, Ordering::SeqCst) >= MAX_STREAMS {
        app.streams.fetch_sub(1, Ordering::SeqCst);
        return error(503, format!("at most {MAX_STREAMS} event streams at once"));
    }
    let guard = StreamSlot(app.clone());
    let frames = futures_util::stream::unfold(guard, |guard| async move {
        if guard.0.stop.load(Ordering::Relaxed) {
            return None;
        }
        tokio::time::sleep(Duration::from_millis(33)).await;
        let mut buf = b"data: ".to_vec();
        let _ = serde_json::to_writer(&mut buf, &state_json(&guard.0));
        buf.extend_from_slice(b"\n\n");
        Some((Ok::<_, Infallible>(Frame::data(Bytes::from(buf))), guard))
    });
    let mut r = Response::new(StreamBody::new(frames).boxed());
    r.headers_mut()
        .insert(CONTENT_TYPE, HeaderValue::from_static("text/event-stream"));
    no_store(r)
}

/// One of the [`MAX_STREAMS`] event streams, given back when the stream ends or its client
/// goes.
struct StreamSlot(Arc<App>);

impl Drop for StreamSlot {
    fn drop(&mut self) {
        self.0.streams.fetch_sub(1, Ordering::SeqCst);
    }
}
