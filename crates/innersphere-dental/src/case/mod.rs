//! A case: one patient's plan from scans to printable wafers, in one file and one call.
//!
//! - `schema`: the case file ([`Case`], versioned JSON, checked whole before any work);
//! - `plan`: runs it ([`run`]): trees, bite, contact map, wafers; [`Plan`] is the answer;
//! - `write`: the output folder ([`write()`]): maps, wafers, `report.html`, `case.json`;
//! - `report`: the self-contained HTML report;
//! - `picture`: its pictures, drawn headlessly.
//!
//! docs/PLAN.md is the surgeon's page; what each step means clinically is there.

mod picture;
mod plan;
mod report;
mod schema;
mod write;

pub use picture::{encode_png, render, Layer, View};
pub use plan::{
    run, ArchMap, InputFile, Plan, PlanBite, PlanEnv, PlanMap, PlanSeconds, PlanSplint, Planned,
    LOWER_MAP, UPPER_MAP,
};
pub use report::report_html;
pub use schema::{
    AutoWord, BiteMethod, BiteSpec, Case, OpenSpec, SplintName, SplintSpec, CASE_INPUT,
    CASE_VERSION, DEFAULT_START_OPENING, MAX_CASE_BYTES, MAX_SPLINTS,
};
pub use write::{check_folder, utc_stamp, write, CASE_FILE, MANIFEST, REPORT};
