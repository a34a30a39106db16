//! The crate's modules import one way, down a ladder: anatomy, columns, occlusion_status ← contact_map ← the bite (occlusion, its limits, reach, bite, free_occlusion) ← splint ← case. Reads every `crate::…` path in
//! the sources (outside their `#[cfg(test)]` modules) and fails on an import from a rung above,
//! or through the crate root's re-exports.

/// The rung of a top-level module of the crate.
fn layer(module: &str) -> Option<u32> {
    Some(match module {
        "anatomy" | "columns" | "occlusion_status" => 0,
        "contact_map" => 1,
        "occlusion" | "occlusion_limits" | "reach" | "bite" | "free_occlusion" => 2,
        "splint" => 3,
        "case" => 4,
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
