//! `report.html`: one self-contained page a lab or a colleague reads (no scripts, no
//! links out; the pictures are PNGs inside it): the bite, the contact map per region (and
//! per tooth with teeth files), left/right balance, each wafer's guarantees and
//! measurements, the inputs' hashes and the library's version.

use super::picture::{render, Layer, View};
use super::plan::{ArchMap, Planned};
use crate::contact_map::{gap_colour, LEGEND};
use base64::Engine as _;
use glam::DVec3;
use innersphere::error::Result;
use innersphere::mesh::Mesh;
use innersphere::pose::Pose;
use std::fmt::Write as _;

/// Picture size (pixels).
const W: u32 = 720;
const H: u32 = 420;
const UPPER: [u8; 3] = [205, 205, 210];
const LOWER: [u8; 3] = [236, 222, 190];
const WAFER: [u8; 3] = [70, 160, 170];

/// Escapes text for HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A PNG as an `<img>` element.
fn img(png: &[u8], alt: &str) -> String {
    format!(
        "<img alt=\"{}\" width=\"{W}\" height=\"{H}\" src=\"data:image/png;base64,{}\">",
        esc(alt),
        base64::engine::general_purpose::STANDARD.encode(png)
    )
}

/// A length in mm with 3 decimals, or "none" for an infinite one.
fn mm(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3}")
    } else {
        "none".into()
    }
}

fn placed(mesh: &Mesh, pose: &Pose) -> Vec<DVec3> {
    mesh.vertices
        .iter()
        .map(|v| pose.transform_point(*v))
        .collect()
}

/// The page, `stamp` (when it was made) on its own line so that two runs differ only there.
pub fn report_html(p: &Planned, stamp: &str) -> Result<String> {
    let plan = &p.plan;
    let f = &p.frame;
    let pose = Pose::from_array(plan.bite.pose).unwrap_or(Pose::IDENTITY);
    let lower_at = placed(&p.lower, &pose);
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>innersphere plan</title>\n<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto;color:#222}}table{{border-collapse:collapse;margin:.5em 0}}td,th{{border:1px solid #bbb;padding:.2em .5em;text-align:right}}th{{background:#eee}}td:first-child{{text-align:left}}.bad{{color:#b00;font-weight:bold}}.ok{{color:#070}}img{{border:1px solid #ddd}}</style></head><body>\n<h1>Bite and wafer plan</h1>\n<p>innersphere {}, case version {}; lengths in mm (the scans were read in {}); trees built with the <code>{}</code> preset.</p>\n<p>Made {}</p>\n",
        esc(plan.library),
        plan.case_version,
        esc(&format!("{:?}", plan.unit).to_lowercase()),
        esc(plan.preset),
        esc(stamp)
    );
    // The bite.
    let b = &plan.bite;
    let _ = write!(
        h,
        "<h2>The bite</h2>\n<p>Method <b>{:?}</b>, contact on the {}; status <b>{:?}</b>; the packings overlap {:.4} mm³ at rest{}.</p>\n<p>Lower arch in the upper's frame (tx ty tz qw qx qy qz): <code>{}</code></p>\n",
        b.method,
        b.contact,
        b.status,
        b.volume,
        if b.candidates > 0 {
            format!("; {} distinct rests found, the best bilateral one chosen", b.candidates)
        } else {
            String::new()
        },
        b.pose.map(|x| format!("{x:.6}")).join(" ")
    );
    let side = render(
        &[
            Layer {
                vertices: &p.upper.vertices,
                mesh: &p.upper,
                colours: None,
                colour: UPPER,
            },
            Layer {
                vertices: &lower_at,
                mesh: &p.lower,
                colours: None,
                colour: LOWER,
            },
        ],
        &View::new(f.left, f.up),
        W,
        H,
    )?;
    h.push_str(&img(
        &side,
        "the arches at the bite, seen from the patient's left",
    ));
    h.push_str("<p>Seen from the patient's left: upper arch grey, lower ivory.</p>\n");

    // The contact map.
    if let (Some(map), Some(gaps)) = (&plan.map, &p.map) {
        h.push_str("<h2>The contact map</h2>\n<p>Each vertex coloured by its exact gap to the other arch: ");
        let mut lo = f64::NEG_INFINITY;
        for (hi, name, rgb) in LEGEND {
            let _ = write!(
                h,
                "<span style=\"background:rgb({},{},{});padding:0 .4em\">{}</span> {} ",
                rgb[0],
                rgb[1],
                rgb[2],
                esc(name),
                if lo.is_finite() {
                    format!("{lo}–{hi}")
                } else {
                    format!("&lt; {hi}")
                }
            );
            lo = hi;
        }
        h.push_str("mm.</p>\n");
        for (arch, title, mesh, vertices, g, toward) in [
            (
                &map.upper,
                "Upper arch, seen from below",
                &p.upper,
                &p.upper.vertices,
                &gaps.gaps_a,
                -f.up,
            ),
            (
                &map.lower,
                "Lower arch at the bite, seen from above",
                &p.lower,
                &lower_at,
                &gaps.gaps_b,
                f.up,
            ),
        ] {
            let colours: Vec<[u8; 3]> = g.iter().map(|&x| gap_colour(x)).collect();
            let pic = render(
                &[Layer {
                    vertices,
                    mesh,
                    colours: Some(&colours),
                    colour: UPPER,
                }],
                &View::new(toward, f.anterior),
                W,
                H,
            )?;
            let _ = writeln!(h, "<h3>{}</h3>", esc(title));
            h.push_str(&img(&pic, title));
            arch_table(&mut h, arch);
        }
    }

    // The wafers.
    for (s, made) in plan.splints.iter().zip(&p.splints) {
        let (Some(r), Some(made)) = (&s.report, made) else {
            let _ = writeln!(
                h,
                "<h2>Wafer “{}”</h2>\n<p class=\"bad\">NOT made: {}</p>",
                esc(&s.name),
                esc(s.error.as_deref().unwrap_or("no reason given"))
            );
            continue;
        };
        let _ = write!(
            h,
            "<h2>Wafer “{}”</h2>\n<p class=\"{}\">{}</p>\n",
            esc(&s.name),
            if r.fit { "ok" } else { "bad" },
            match &s.file {
                Some(file) => format!("Fit to print: {}", esc(file)),
                None => "NOT fit to print: not written (see the failed checks)".into(),
            }
        );
        let at = Pose::from_array(r.pose).unwrap_or(pose);
        let lower_there = placed(&p.lower, &at);
        let pic = render(
            &[
                Layer {
                    vertices: &made.mesh.vertices,
                    mesh: &made.mesh,
                    colours: None,
                    colour: WAFER,
                },
                Layer {
                    vertices: &lower_there,
                    mesh: &p.lower,
                    colours: None,
                    colour: LOWER,
                },
            ],
            &View::new(f.up * 0.8 + f.anterior * 0.6, f.anterior),
            W,
            H,
        )?;
        h.push_str(&img(&pic, "the wafer seated on the lower arch"));
        let _ = write!(
            h,
            "<p>Seated on the lower arch, seen from above and in front. Opened {:.2} mm at the incisors about the hinge.</p>\n<table><tr><th>check</th><th>result</th><th>detail</th></tr>\n",
            r.opened
        );
        for c in &r.checks {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td class=\"{}\">{}</td><td style=\"text-align:left\">{}</td></tr>",
                esc(c.name),
                if c.ok { "ok" } else { "bad" },
                if c.ok { "pass" } else { "FAIL" },
                esc(&c.detail)
            );
        }
        let _ = write!(
            h,
            "</table>\n<table><tr><th>volume mm³</th><th>triangles</th><th>bodies</th><th>thinnest mm</th><th>to upper mm</th><th>to lower mm</th><th>coverage upper</th><th>coverage lower</th><th>perforated mm²</th></tr>\n<tr><td>{:.1}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td><td>{:.1} %</td><td>{:.1} %</td><td>{:.2}</td></tr></table>\n",
            r.volume,
            r.triangles,
            r.bodies,
            r.min_thickness,
            r.min_distance_a,
            r.min_distance_b,
            100.0 * r.coverage_a,
            100.0 * r.coverage_b,
            r.perforated_area
        );
    }

    // The inputs.
    h.push_str("<h2>Inputs</h2>\n<table><tr><th>role</th><th>file</th><th>bytes</th><th>BLAKE3</th></tr>\n");
    for i in &plan.inputs {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td><code>{}</code></td></tr>",
            i.role,
            esc(&i.file),
            i.bytes,
            i.blake3
        );
    }
    h.push_str("</table>\n<p>The same inputs and case give the same files: run <code>ist plan CASE.json -o DIR</code> again to check.</p>\n</body></html>\n");
    Ok(h)
}

/// One arch's tables: per region, per tooth when given, and the balance.
fn arch_table(h: &mut String, a: &ArchMap) {
    let _ = writeln!(
        h,
        "<p>{} vertices; least gap {} mm; {} vertices inside the other arch. Contact within 0.1 mm: left {:.2} mm², right {:.2} mm² ({}).</p>",
        a.vertices,
        mm(a.min_gap),
        a.vertices_inside,
        a.balance.left,
        a.balance.right,
        if a.balance.left_share.is_finite() {
            format!("{:.0} % left", 100.0 * a.balance.left_share)
        } else {
            "no contact".into()
        }
    );
    h.push_str("<table><tr><th>region</th><th>least gap mm</th><th>mm² within 0.1</th><th>mm² within 0.2</th><th>spots</th></tr>\n");
    for r in &a.regions {
        let s = &r.summary;
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{:.2}</td><td>{:.2}</td><td>{}</td></tr>",
            r.region,
            mm(s.min_gap),
            s.area_within_0_1,
            s.area_within_0_2,
            s.spots
        );
    }
    h.push_str("</table>\n");
    if let Some(teeth) = &a.teeth {
        h.push_str("<table><tr><th>tooth</th><th>least gap mm</th><th>mm² within 0.1</th><th>mm² within 0.2</th><th>spots</th></tr>\n");
        for s in teeth {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{:.2}</td><td>{:.2}</td><td>{}</td></tr>",
                s.tooth,
                mm(s.min_gap),
                s.area_within_0_1,
                s.area_within_0_2,
                s.spots
            );
        }
        h.push_str("</table>\n");
    }
}
