//! What the `ist` end-to-end tests share: a temporary folder and running the binary.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A temporary folder, removed when dropped.
pub struct TempDir(pub PathBuf);

impl TempDir {
    /// A fresh folder named after the test file (`prefix`), the process and `name`.
    pub fn new(prefix: &str, name: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("{prefix}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    /// `file` in the folder.
    pub fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }

    /// Names of the files in the folder that look like left-over temporary files.
    pub fn temporaries(&self) -> Vec<String> {
        std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.') || n.ends_with(".tmp"))
            .collect()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `ist` with `args`; trees built from meshes go to a cache folder of this test process,
/// never the user's.
pub fn ist(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ist"))
        .args(args)
        .env(
            "IST_CACHE",
            std::env::temp_dir().join(format!("ist-test-cache-{}", std::process::id())),
        )
        .output()
        .expect("ist runs")
}

/// The exit code.
pub fn code(out: &Output) -> i32 {
    out.status.code().expect("ist exited normally")
}

/// Standard output as text.
pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Standard error as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A path as an argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
