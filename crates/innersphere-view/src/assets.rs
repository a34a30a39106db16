//! The page's files, embedded in the binary (no network and no npm at run time): a fixed
//! table, so that no request can name a file outside it.

/// `(path under /assets/, content type, bytes)`.
const FILES: &[(&str, &str, &[u8])] = &[
    (
        "index.html",
        "text/html; charset=utf-8",
        include_bytes!("../assets/index.html"),
    ),
    (
        "app.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../assets/app.js"),
    ),
    (
        "style.css",
        "text/css; charset=utf-8",
        include_bytes!("../assets/style.css"),
    ),
    (
        "vendor/three.module.min.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../assets/vendor/three.module.min.js"),
    ),
    (
        "vendor/OrbitControls.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../assets/vendor/OrbitControls.js"),
    ),
    (
        "vendor/TransformControls.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../assets/vendor/TransformControls.js"),
    ),
    (
        "vendor/LICENSE-three.txt",
        "text/plain; charset=utf-8",
        include_bytes!("../assets/vendor/LICENSE-three.txt"),
    ),
];

/// The embedded file at `path` (relative to `/assets/`).
pub(crate) fn get(path: &str) -> Option<(&'static str, &'static [u8])> {
    FILES.iter().find(|f| f.0 == path).map(|f| (f.1, f.2))
}
