//! The crate's modules import one way, down a ladder: device, mat6, realtime ← body ← step ← model ← deadline, blend ← servo, render (the loop's options and tick are render's) ← multirate. Reads every `crate::…` path in
//! the sources (outside their `#[cfg(test)]` modules) and fails on an import from a rung above,
//! or through the crate root's re-exports.

/// The rung of a top-level module of the crate.
fn layer(module: &str) -> Option<u32> {
    Some(match module {
        "device" | "mat6" | "realtime" => 0,
        "body" => 1,
        "step" => 2,
        "model" => 3,
        "deadline" | "blend" => 4,
        "servo" | "render" => 5,
        "multirate" => 6,
        _ => return None,
    })
}

#[test]
fn modules_import_down_the_ladder_by_their_own_paths() {
    innersphere_testkit::layering::assert_imports_down_the_ladder(
        env!("CARGO_MANIFEST_DIR"),
        layer,
    );
}
