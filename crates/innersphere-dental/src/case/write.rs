//! Writes a [`Planned`] into its output folder: the contact map's PLYs, each fit wafer's
//! STL and 3MF, `report.html`, `case.json` (the case as run, replayable) and `plan-files.txt`
//! (what this plan wrote). Every file goes through a temporary file renamed into place.
//!
//! The folder is the plan's: it must be new, empty, or hold a previous plan's files (its
//! `plan-files.txt`). Nothing else in it is touched; of the previous plan's files, those
//! this plan does not write again are removed (a wafer that is no longer fit must not be
//! left beside a report that says so).

use super::plan::{Planned, LOWER_MAP, UPPER_MAP};
use super::report::report_html;
use crate::contact_map::save_ply;
use innersphere::error::{Error, Result};
use innersphere::pose::Pose;
use std::path::{Path, PathBuf};

/// The list of the files a plan wrote, in its folder.
pub const MANIFEST: &str = "plan-files.txt";
/// The report's file.
pub const REPORT: &str = "report.html";
/// The case as run.
pub const CASE_FILE: &str = "case.json";

/// A plain file name a manifest may list (no folder, no `..`).
fn plain(name: &str) -> bool {
    !name.is_empty()
        && name != "."
        && name != ".."
        && !name.contains(['/', '\\', ':'])
        && name.len() <= 255
}

/// Refuses an output folder a plan may not write into (a file, or a folder of files no plan
/// wrote): what [`write()`] checks, to be asked before the work.
pub fn check_folder(dir: &Path) -> Result<()> {
    previous(dir).map(|_| ())
}

/// The previous plan's files in `dir` (empty for a new or empty folder); an error for a
/// folder holding anything else.
fn previous(dir: &Path) -> Result<Vec<String>> {
    let io = |e: std::io::Error| Error::InvalidOption(format!("{}: {e}", dir.display()));
    match std::fs::metadata(dir) {
        Err(_) => return Ok(vec![]),
        Ok(m) if !m.is_dir() => {
            return Err(Error::InvalidOption(format!(
                "{} is a file, not a folder: give a new or empty folder for the plan's outputs",
                dir.display()
            )))
        }
        Ok(_) => {}
    }
    let manifest = dir.join(MANIFEST);
    if !manifest.is_file() {
        if std::fs::read_dir(dir).map_err(io)?.next().is_some() {
            return Err(Error::InvalidOption(format!(
                "{} holds files that no plan wrote (no {MANIFEST}): give a new or empty folder, so that nothing of yours is overwritten",
                dir.display()
            )));
        }
        return Ok(vec![]);
    }
    let text = std::fs::read(&manifest).map_err(io)?;
    if text.len() > 1 << 16 {
        return Err(Error::InvalidOption(format!(
            "{} is not a plan's list of files (too long)",
            manifest.display()
        )));
    }
    Ok(String::from_utf8_lossy(&text)
        .lines()
        .filter(|l| plain(l))
        .map(str::to_string)
        .collect())
}

/// Writes `p` into `dir` (see the module docs); `stamp` goes on the report's "Made" line.
/// Refuses to write over an input. Returns the files written.
pub fn write(p: &Planned, dir: &Path, stamp: &str) -> Result<Vec<PathBuf>> {
    let old = previous(dir)?;
    std::fs::create_dir_all(dir)
        .map_err(|e| Error::InvalidOption(format!("{}: {e}", dir.display())))?;
    let mut names: Vec<String> = vec![];
    if let Some(map) = &p.map {
        names.push(UPPER_MAP.into());
        names.push(LOWER_MAP.into());
        let _ = map;
    }
    for s in &p.plan.splints {
        if let Some(f) = &s.file {
            names.push(f.clone());
            names.push(format!("{}.3mf", s.name));
        }
    }
    names.push(REPORT.into());
    names.push(CASE_FILE.into());
    let c = &p.case;
    let mut inputs: Vec<&Path> = vec![&c.upper, &c.lower];
    inputs.extend(c.teeth_upper.as_deref());
    inputs.extend(c.teeth_lower.as_deref());
    let paths: Vec<PathBuf> = names.iter().map(|n| dir.join(n)).collect();
    for path in &paths {
        innersphere::output::ensure_not_input(path, &inputs)?;
    }
    innersphere::output::ensure_not_input(&dir.join(MANIFEST), &inputs)?;

    if let Some(map) = &p.map {
        let pose = Pose::from_array(p.plan.bite.pose)
            .map_err(|e| Error::InvalidOption(format!("the bite pose: {e}")))?;
        save_ply(&dir.join(UPPER_MAP), &p.upper, &Pose::IDENTITY, &map.gaps_a)?;
        save_ply(&dir.join(LOWER_MAP), &p.lower, &pose, &map.gaps_b)?;
    }
    for (s, made) in p.plan.splints.iter().zip(&p.splints) {
        if let (Some(f), Some(made)) = (&s.file, made) {
            innersphere::mesh::save(&made.mesh, &dir.join(f))?;
            let three = crate::splint::threemf::to_3mf_bytes(&made.mesh, &s.name)?;
            innersphere::output::write_file(&dir.join(format!("{}.3mf", s.name)), &three)?;
        }
    }
    innersphere::output::write_file(&dir.join(REPORT), report_html(p, stamp)?.as_bytes())?;
    // The case as run, its paths absolute: replayable from anywhere on this machine.
    let mut case = p.case.clone();
    let abs = |q: &Path| std::path::absolute(q).unwrap_or_else(|_| q.to_path_buf());
    case.upper = abs(&case.upper);
    case.lower = abs(&case.lower);
    case.teeth_upper = case.teeth_upper.as_deref().map(abs);
    case.teeth_lower = case.teeth_lower.as_deref().map(abs);
    innersphere::output::write_file(&dir.join(CASE_FILE), case.to_json().as_bytes())?;
    // The previous plan's files not written again.
    for name in old
        .iter()
        .filter(|n| !names.contains(n) && n.as_str() != MANIFEST)
    {
        let path = dir.join(name);
        if path.is_file() {
            let _ = std::fs::remove_file(&path);
        }
    }
    let mut manifest = names.join("\n");
    manifest.push('\n');
    innersphere::output::write_file(&dir.join(MANIFEST), manifest.as_bytes())?;
    Ok(paths)
}

/// The time now in UTC as `YYYY-MM-DD hh:mm:ss UTC` (the report's stamp).
pub fn utc_stamp() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    // Days since 1970-01-01 to a civil date (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}
