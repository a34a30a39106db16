//! The wafer as a 3MF file: the format of current printer software (one zip holding the
//! model's XML, in millimetres), beside the STL labs have always taken. The same `f32`
//! coordinates as the STL ([`written`](super::written)), and the same bytes run after run
//! (the zip entries dated 1980-01-01, as the `zip` crate does without a clock).

use innersphere::error::{Error, Result};
use innersphere::mesh::Mesh;
use std::fmt::Write as _;
use std::io::Write as _;

const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>
"#;

const RELS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>
"#;

/// The model part: one object, its vertices as `f32` (mm) and its triangles.
fn model(mesh: &Mesh, name: &str) -> String {
    let mut x = String::with_capacity(64 * (mesh.vertices.len() + mesh.triangles.len()));
    x.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" xml:lang=\"en-US\" xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n");
    let _ = writeln!(
        x,
        "<metadata name=\"Title\">{}</metadata>",
        name.replace('&', "&amp;").replace('<', "&lt;")
    );
    x.push_str("<resources><object id=\"1\" type=\"model\"><mesh><vertices>\n");
    for v in &mesh.vertices {
        let _ = writeln!(
            x,
            "<vertex x=\"{}\" y=\"{}\" z=\"{}\"/>",
            v.x as f32, v.y as f32, v.z as f32
        );
    }
    x.push_str("</vertices><triangles>\n");
    for t in &mesh.triangles {
        let _ = writeln!(
            x,
            "<triangle v1=\"{}\" v2=\"{}\" v3=\"{}\"/>",
            t[0], t[1], t[2]
        );
    }
    x.push_str(
        "</triangles></mesh></object></resources><build><item objectid=\"1\"/></build></model>\n",
    );
    x
}

/// What a wafer may be written as: binary STL, OBJ (each optionally gzip-compressed) or 3MF.
pub const WAFER_FILE: innersphere::output::OutputKind = innersphere::output::OutputKind {
    what: "the wafer (binary STL, OBJ or 3MF)",
    extensions: &["stl", "stl.gz", "obj", "obj.gz", "3mf"],
};

/// Writes the wafer `mesh` in the format its name says ([`WAFER_FILE`]): 3MF here (its object
/// titled by the file's stem), STL or OBJ by `innersphere::mesh::save`.
pub fn save_wafer(mesh: &Mesh, path: &std::path::Path) -> Result<()> {
    WAFER_FILE.check(path)?;
    let name = path.to_string_lossy().to_ascii_lowercase();
    if name.ends_with(".3mf") {
        let title = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        innersphere::output::write_file(path, &to_3mf_bytes(mesh, &title)?)
    } else {
        innersphere::mesh::save(mesh, path)
    }
}

/// The 3MF file of `mesh` (mm), its object titled `name`.
pub fn to_3mf_bytes(mesh: &Mesh, name: &str) -> Result<Vec<u8>> {
    let fail = |e: String| Error::InvalidOption(format!("writing the 3MF file: {e}"));
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .last_modified_time(zip::DateTime::default())
        .unix_permissions(0o644);
    for (path, text) in [
        ("[Content_Types].xml", CONTENT_TYPES.to_string()),
        ("_rels/.rels", RELS.to_string()),
        ("3D/3dmodel.model", model(mesh, name)),
    ] {
        zip.start_file(path, opts)
            .map_err(|e| fail(e.to_string()))?;
        zip.write_all(text.as_bytes())
            .map_err(|e| fail(e.to_string()))?;
    }
    Ok(zip.finish().map_err(|e| fail(e.to_string()))?.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use std::io::Read as _;

    /// A tetrahedron: three parts in the zip, the model's vertices and triangles as given,
    /// the same bytes twice.
    #[test]
    fn a_tetrahedron_reads_back() {
        let m = Mesh {
            vertices: vec![
                DVec3::ZERO,
                DVec3::new(1.5, 0.0, 0.0),
                DVec3::new(0.0, 2.25, 0.0),
                DVec3::new(0.0, 0.0, -3.125),
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        };
        let bytes = to_3mf_bytes(&m, "wafer <final>").unwrap();
        assert_eq!(bytes, to_3mf_bytes(&m, "wafer <final>").unwrap());
        let mut z = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
        assert_eq!(z.len(), 3);
        let mut text = String::new();
        z.by_name("3D/3dmodel.model")
            .unwrap()
            .read_to_string(&mut text)
            .unwrap();
        assert_eq!(text.matches("<vertex ").count(), 4);
        assert_eq!(text.matches("<triangle ").count(), 4);
        assert!(text.contains("<vertex x=\"0\" y=\"0\" z=\"-3.125\"/>"));
        assert!(text.contains("<triangle v1=\"1\" v2=\"2\" v3=\"3\"/>"));
        assert!(text.contains("wafer &lt;final>"));
    }
}
