//! How a closing of B onto A ended: one word, the same at every door (the library, `ist
//! occlude`'s text, `--json` and exit code, Python's `occlude` and `occlude_many`).
//!
//! "Converged" means what a planner reads it as: B rests **in contact** with A, held there
//! by the contact. Everything else has a word of its own, so that no answer that is still
//! open, still moving, or on the far side of A passes for a bite. Inputs that cannot make a
//! bite at all (options out of range, arches that do not face each other, a start far
//! away) are refused with an error before any closing and have no status.

use std::collections::BTreeMap;

/// How one closing ended (serialized in snake_case: `"converged"`, `"no_contact"`,
/// `"time_limit"`, `"passed_through"`, `"escaped"`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum OcclusionStatus {
    /// At rest in contact: B touches A (contact patches, an overlap volume above 0), its
    /// centre of mass moved less than the rest distance (and it turned less than the rest
    /// angle) over the rest window, and the net wrench on it (the closing force, the
    /// contact's and the joints') is below [`BALANCE`] of the closing force (the torque:
    /// of the force at B's radius of gyration).
    Converged,
    /// At rest, balanced, without touching A: something other than the contact (the joints)
    /// holds B open.
    NoContact,
    /// Still moving (or not balanced) when the time allowed ran out.
    TimeLimit,
    /// B ended on the far side of A along the closing axis (its centre of mass crossed A's,
    /// having started on the near side): the contact did not hold B and it went through A
    /// (a force too large for the contact's stiffness, or bodies too thin for it), or it slid
    /// off past A's side. The closing stops there.
    PassedThrough,
    /// B moved away from A: farther from its start than its start's distance to A's centre
    /// of mass plus both bodies' radii, where it can no longer touch A. The closing stops
    /// there.
    Escaped,
}

/// At rest, the net wrench on B is at most this share of the closing force (and the net
/// torque of the closing force at B's radius of gyration). At rest B moves by less than the
/// rest distance per window, so its damping carries a ten-thousandth of the closing force
/// or less; a larger imbalance is a body that is still being pushed, only slowly.
pub const BALANCE: f64 = 0.05;

impl OcclusionStatus {
    /// Every status, in the order of the type (the order of counts and exit codes' docs).
    pub const ALL: [OcclusionStatus; 5] = [
        OcclusionStatus::Converged,
        OcclusionStatus::NoContact,
        OcclusionStatus::TimeLimit,
        OcclusionStatus::PassedThrough,
        OcclusionStatus::Escaped,
    ];

    /// The status's word, as serialized.
    pub fn as_str(self) -> &'static str {
        match self {
            OcclusionStatus::Converged => "converged",
            OcclusionStatus::NoContact => "no_contact",
            OcclusionStatus::TimeLimit => "time_limit",
            OcclusionStatus::PassedThrough => "passed_through",
            OcclusionStatus::Escaped => "escaped",
        }
    }

    /// What it means, in a sentence for a planner.
    pub fn describe(self) -> &'static str {
        match self {
            OcclusionStatus::Converged => "B rests in contact with A, held by the contact",
            OcclusionStatus::NoContact => {
                "B came to rest without touching A: the joints hold it open (is the reference \
                 pose the bite?)"
            }
            OcclusionStatus::TimeLimit => {
                "B was still moving when the time allowed ran out (allow more time, or start \
                 closer)"
            }
            OcclusionStatus::PassedThrough => {
                "B ended on the far side of A along the closing axis: it went through A (a \
                 force too large for the contact stiffness, or arches too thin for it) or slid \
                 off past it; the pose is not a bite"
            }
            OcclusionStatus::Escaped => {
                "B moved away from A and can no longer touch it (is the closing axis towards \
                 A?); the pose is not a bite"
            }
        }
    }
}

impl std::fmt::Display for OcclusionStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// How many closings ended in each status; every status is present (0 where none).
pub type StatusCounts = BTreeMap<OcclusionStatus, usize>;

/// Counts of `statuses`, with every status present.
pub fn count_statuses(statuses: impl IntoIterator<Item = OcclusionStatus>) -> StatusCounts {
    let mut counts: StatusCounts = OcclusionStatus::ALL.iter().map(|s| (*s, 0)).collect();
    for s in statuses {
        *counts.entry(s).or_insert(0) += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_status_serializes_as_its_word_and_back() {
        for s in OcclusionStatus::ALL {
            let j = serde_json::to_value(s).unwrap();
            assert_eq!(j, serde_json::Value::String(s.as_str().into()));
            assert_eq!(s.to_string(), s.as_str());
            let back: OcclusionStatus = serde_json::from_value(j).unwrap();
            assert_eq!(back, s);
        }
        let words: Vec<&str> = OcclusionStatus::ALL.iter().map(|s| s.as_str()).collect();
        assert_eq!(
            words,
            [
                "converged",
                "no_contact",
                "time_limit",
                "passed_through",
                "escaped"
            ]
        );
    }

    #[test]
    fn counts_have_every_status_and_serialize_as_a_map_of_words() {
        use OcclusionStatus::*;
        let c = count_statuses([Converged, TimeLimit, Converged, Escaped]);
        assert_eq!(c.len(), 5);
        assert_eq!(
            (
                c[&Converged],
                c[&NoContact],
                c[&TimeLimit],
                c[&PassedThrough],
                c[&Escaped]
            ),
            (2, 0, 1, 0, 1)
        );
        assert_eq!(
            serde_json::to_value(&c).unwrap(),
            serde_json::json!({"converged": 2, "no_contact": 0, "time_limit": 1,
                               "passed_through": 0, "escaped": 1})
        );
    }
}
