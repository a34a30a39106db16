//! The bugs the fuzzer found, each as a small hand-made input with the reason (the crash
//! files themselves are replayed by `tests/corpus.rs` from `regressions/<target>/`).

use innersphere::tree::{file, SphereTree, NO_PARENT};
use innersphere::Error;
use innersphere_fuzz::seeds::small_tree;

/// A node that is nobody's child (an orphan) at depth 65535 with a child: validating the
/// child computes the orphan's depth + 1, which does not fit a `u16`. An unchecked add panics
/// with overflow checks (debug builds, and the fuzzer's `-a` builds: "attempt to add with
/// overflow" in `tree/mod.rs` `validate_structure`) and wraps to 0 without them. Found by
/// `tree_file` (crash-11b287df..., 627 bytes, and two more of the same cause). The answer
/// must be an error, never a panic, in every build.
fn orphan_at_max_depth() -> SphereTree {
    let mut t = small_tree();
    // Node 0: a leaf root. Node 1: an orphan at depth u16::MAX with node 2 as its child.
    t.child_count = vec![0, 1, 0];
    t.first_child = vec![0, 2, 0];
    t.parent = vec![NO_PARENT, 0, 1];
    t.depth = vec![0, u16::MAX, 0];
    t
}

#[test]
fn an_orphan_at_the_largest_depth_is_an_error_not_a_panic() {
    let t = orphan_at_max_depth();
    let err = t.validate_structure().expect_err("an orphan node");
    assert!(matches!(err, Error::CorruptTree(_)), "{err}");
    // The same through the file reader (the size and checksum are right).
    let err = file::from_bytes(&file::to_bytes(&t)).expect_err("an orphan node");
    assert!(matches!(err, Error::CorruptTree(_)), "{err}");
}
