//! What a hostile or broken client can do to the viewer's server, and cannot: slow bodies,
//! pipelined requests never read, a huge header, bare-LF and HTTP/2.0 request lines, too
//! many connections, HEAD, and a far pose in haptic mode. Each test has a server of its own.

use innersphere_view::{serve, Scene, ServeOptions};
use serde_json::Value;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The header and body timeouts of the tests' servers.
const TIMEOUT: Duration = Duration::from_secs(1);

fn scene() -> &'static Scene {
    static S: OnceLock<Scene> = OnceLock::new();
    S.get_or_init(|| Scene::demo().unwrap())
}

/// A server on its own port.
fn server(max_connections: usize) -> SocketAddr {
    let (tx, rx) = std::sync::mpsc::channel();
    let s = scene().clone();
    std::thread::spawn(move || {
        // Short timeouts, so that the tests that wait for them do not wait long.
        let opts = ServeOptions {
            port: 0,
            max_connections,
            header_timeout: TIMEOUT,
            body_timeout: TIMEOUT,
            ..Default::default()
        };
        serve(s, opts, move |addr| tx.send(addr).unwrap()).unwrap();
    });
    rx.recv_timeout(Duration::from_secs(30)).unwrap()
}

/// (status, head, body) of one request on a fresh connection; `raw` is sent as it is.
fn raw(addr: SocketAddr, raw: &[u8]) -> (u16, String, Vec<u8>) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let _ = s.write_all(raw);
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out).to_string();
    let code = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let end = out
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .map_or(out.len(), |i| i + 4);
    (
        code,
        text[..end.min(text.len())].to_string(),
        out[end..].to_vec(),
    )
}

fn get(addr: SocketAddr, path: &str) -> (u16, Duration) {
    let t = Instant::now();
    let (code, _, _) = raw(
        addr,
        format!("GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n").as_bytes(),
    );
    (code, t.elapsed())
}

#[test]
fn slow_clients_hold_up_nobody_else() {
    let addr = server(512);
    // Four clients that promise a 60,000-byte body and send one byte, four that pipeline
    // requests and never read an answer.
    let mut slow = vec![];
    for _ in 0..4 {
        let mut s = TcpStream::connect(addr).unwrap();
        s.write_all(b"POST /api/pose HTTP/1.1\r\nHost: x\r\nContent-Length: 60000\r\n\r\n{")
            .unwrap();
        slow.push(s);
    }
    for _ in 0..4 {
        let mut s = TcpStream::connect(addr).unwrap();
        let one = b"GET /api/spheres?body=a HTTP/1.1\r\nHost: x\r\n\r\n";
        for _ in 0..200 {
            if s.write_all(one).is_err() {
                break;
            }
        }
        slow.push(s);
    }
    // Everyone else is answered at once.
    let mut worst = Duration::ZERO;
    for _ in 0..50 {
        let (code, took) = get(addr, "/api/state");
        assert_eq!(code, 200);
        worst = worst.max(took);
    }
    assert!(worst < Duration::from_secs(1), "a request took {worst:?}");
    // The slow bodies are answered 408 once their time is up.
    let mut s = slow.remove(0);
    s.set_read_timeout(Some(TIMEOUT + Duration::from_secs(10)))
        .unwrap();
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out);
    assert!(text.starts_with("HTTP/1.1 408"), "{text}");
    assert!(text.contains("did not arrive"), "{text}");
}

#[test]
fn a_huge_header_is_refused_without_being_read() {
    let addr = server(512);
    let before = peak_kib();
    // 50 MB of one header line: the server stops at its limit, answers 431 and closes.
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    s.write_all(b"GET /api/info HTTP/1.1\r\nHost: x\r\nX-Big: ")
        .unwrap();
    let chunk = vec![b'a'; 1 << 20];
    for _ in 0..50 {
        if s.write_all(&chunk).is_err() {
            break;
        }
    }
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out);
    assert!(text.starts_with("HTTP/1.1 431"), "{text}");
    let grew = peak_kib().saturating_sub(before);
    assert!(grew < 20 * 1024, "the peak memory grew by {grew} KiB");
    assert_eq!(get(addr, "/api/state").0, 200);
}

/// Peak resident memory of this process (KiB).
fn peak_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|n| n.parse().ok())
        })
        .unwrap_or(0)
}

#[test]
fn odd_requests_get_an_answer_and_the_connection_closes() {
    let addr = server(512);
    // HEAD: the GET's head, no body.
    let (code, head, body) = raw(
        addr,
        b"HEAD /api/info HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n",
    );
    assert_eq!(code, 200, "{head}");
    assert!(head
        .to_ascii_lowercase()
        .contains("content-type: application/json"));
    assert!(body.is_empty());
    // Bare LF line endings: answered (read as the request it is), not left hanging.
    let (code, head, _) = raw(
        addr,
        b"GET /api/info HTTP/1.1\nHost: x\nConnection: close\n\n",
    );
    assert!(code == 200 || (400..500).contains(&code), "{head}");
    // HTTP/2.0 over an HTTP/1 connection, and garbage: an error, then closed.
    for req in [
        &b"GET /api/info HTTP/2.0\r\nHost: x\r\n\r\n"[..],
        b"\x16\x03\x01\x02\x00 hello\r\n\r\n",
    ] {
        let (code, head, _) = raw(addr, req);
        assert!((400..600).contains(&code), "{head}");
    }
    // A connection that sends nothing is closed after the header timeout.
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let t = Instant::now();
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    assert!(
        t.elapsed() < TIMEOUT + Duration::from_secs(5),
        "{:?}",
        t.elapsed()
    );
}

#[test]
fn connections_over_the_cap_are_told_so() {
    let addr = server(8);
    let held: Vec<TcpStream> = (0..8).map(|_| TcpStream::connect(addr).unwrap()).collect();
    std::thread::sleep(Duration::from_millis(200));
    let (code, head, body) = raw(addr, b"GET /api/state HTTP/1.1\r\nHost: x\r\n\r\n");
    assert_eq!(code, 503, "{head}");
    let v: Value = serde_json::from_slice(&body).unwrap();
    assert!(
        v["error"].as_str().unwrap().contains("8 connections"),
        "{v}"
    );
    drop(held);
    // The slots come back when those connections go.
    let t = Instant::now();
    loop {
        if get(addr, "/api/state").0 == 200 {
            break;
        }
        assert!(t.elapsed() < Duration::from_secs(10));
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_far_pose_in_haptic_mode_leaves_the_tool_finite() {
    let addr = server(512);
    let post = |path: &str, body: &str| {
        raw(
            addr,
            format!(
                "POST {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\nContent-Length: {}\r\n\r\n{body}",
                body.len()
            )
            .as_bytes(),
        )
        .0
    };
    assert_eq!(post("/api/mode", r#"{"mode": "haptic"}"#), 200);
    // Once the loop runs the haptic mode (entering it puts the tool at the device's pose).
    let state = || {
        let (_, _, body) = raw(
            addr,
            b"GET /api/state HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n",
        );
        serde_json::from_slice::<Value>(&body).unwrap()
    };
    let t = Instant::now();
    while state()["mode"] != "haptic" {
        assert!(t.elapsed() < Duration::from_secs(5));
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(
        post("/api/pose", r#"{"pose_b": [1e300, 0, 0, 1, 0, 0, 0]}"#),
        200
    );
    std::thread::sleep(Duration::from_millis(300));
    let v = state();
    let pose: Vec<f64> = v["pose_b"]
        .as_array()
        .unwrap_or_else(|| panic!("{v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(pose.iter().all(|x| x.is_finite()), "{v}");
    // It moves towards the far pose no faster than a hand: within 0.3 s, under 0.2 m.
    assert!(pose[0].abs() < 200.0, "{v}");
}
