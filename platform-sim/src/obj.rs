//! A robust Wavefront OBJ geometry reader.
//!
//! Reads vertex positions (`v`) and faces (`f`, any polygon size, `v`,
//! `v/vt`, `v//vn`, `v/vt/vn` and negative indices), fan-triangulating
//! polygons. Materials (`usemtl`, `mtllib`), groups, smoothing, normals and
//! texture coordinates are ignored, so Sweet Home 3D models whose MTL files or
//! material names are missing still load.
//!
//! # Why not `tobj`
//! The maintained OBJ crate reads the same triangles (the differential test
//! `tests/obj_tobj.rs` compares both on the 63 models of the shared Sweet
//! Home 3D homes and on synthetic files), but it stores positions as `f32`
//! unless its `use_f64` feature is on, and that feature changes the types of
//! `tobj`'s public API for every crate of a build, so a library must not
//! enable it. Read as `f32`, 156,102 of the 158,397 coordinates of those
//! models change (measured by the same test), and with them the homes'
//! geometry, navigability and results. `tobj` also reports errors without a
//! line number ([`SceneError::Obj`] has one). This reader is fifty lines,
//! fuzzed (`sornav-fuzz`) and tested against `tobj`; `tobj` is a
//! dev-dependency only.

use nalgebra::Point3;

use crate::SceneError;
use crate::scene::Aabb;

/// Triangle geometry of an OBJ model (in the model's own units and axes).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjMesh {
    /// Vertex positions.
    pub vertices: Vec<Point3<f64>>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

impl ObjMesh {
    /// Bounds of the vertices used by triangles. Indices out of range (the
    /// fields are public; [`parse_obj`] never produces them) are ignored;
    /// without any valid index the box is empty ([`Aabb::empty`]).
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::empty();
        for t in &self.triangles {
            for &i in t {
                if let Some(v) = self.vertices.get(i as usize) {
                    b.include(v);
                }
            }
        }
        b
    }
}

/// Parses OBJ text. `file` names the source in errors.
///
/// # Errors
/// [`SceneError::Obj`] with the line of a malformed number, a face with fewer
/// than three vertices, an index out of range or a non-finite coordinate.
///
/// # Complexity
/// O(n) in the text length.
pub fn parse_obj(text: &str, file: &str) -> Result<ObjMesh, SceneError> {
    let err = |line: usize, message: String| SceneError::Obj {
        file: file.to_string(),
        line,
        message,
    };
    let mut mesh = ObjMesh::default();
    let mut face: Vec<u32> = Vec::with_capacity(8);
    for (ln, raw) in text.lines().enumerate() {
        let line = ln + 1;
        let l = raw.split('#').next().unwrap_or("").trim();
        let mut it = l.split_ascii_whitespace();
        match it.next() {
            Some("v") => {
                let mut c = [0.0f64; 3];
                for (k, v) in c.iter_mut().enumerate() {
                    let tok = it
                        .next()
                        .ok_or_else(|| err(line, format!("vertex has {k} coordinates")))?;
                    *v = tok
                        .parse()
                        .map_err(|_| err(line, format!("bad coordinate `{tok}`")))?;
                    if !v.is_finite() {
                        return Err(err(line, format!("non-finite coordinate `{tok}`")));
                    }
                }
                mesh.vertices.push(Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                face.clear();
                let n = mesh.vertices.len() as i64;
                for tok in it {
                    let vi = tok.split('/').next().unwrap_or("");
                    let i: i64 = vi
                        .parse()
                        .map_err(|_| err(line, format!("bad face index `{tok}`")))?;
                    let idx = if i > 0 { i - 1 } else { n + i };
                    if i == 0 || idx < 0 || idx >= n {
                        return Err(err(line, format!("face index {i} out of range (1..={n})")));
                    }
                    face.push(idx as u32);
                }
                if face.len() < 3 {
                    return Err(err(line, format!("face with {} vertices", face.len())));
                }
                for k in 1..face.len() - 1 {
                    mesh.triangles.push([face[0], face[k], face[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_faces_and_ignores_materials() {
        let m = parse_obj(
            "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl flwhite1\nf 1/1/1 2/2/2 3/3/3 4/4/4\nf -1 -2 -3\n",
            "t.obj",
        )
        .unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
        assert_eq!(m.bounds().max, Point3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn reports_line_of_errors() {
        let e = parse_obj("v 0 0 0\nv 1 x 0\n", "bad.obj").unwrap_err();
        assert!(matches!(e, SceneError::Obj { line: 2, .. }), "{e}");
        let e = parse_obj("v 0 0 0\nf 1 2 3\n", "bad.obj").unwrap_err();
        assert!(matches!(e, SceneError::Obj { line: 2, .. }), "{e}");
        let e = parse_obj("v 0 0 NaN\n", "bad.obj").unwrap_err();
        assert!(matches!(e, SceneError::Obj { line: 1, .. }), "{e}");
    }
}
