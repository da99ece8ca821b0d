//! Differential test of the OBJ reader against `tobj` (the maintained OBJ
//! crate), on every model of the shared Sweet Home 3D homes and on small
//! synthetic files: both readers must produce the same triangles.
//!
//! Why `sornav_platform_sim::obj` stays hand-written (measured here; see
//! also the module docs of `obj`): `tobj` keeps positions as `f32` unless
//! its `use_f64` feature is on, a feature that changes the types of its
//! public API for every crate in a build (a library must not switch it on),
//! while the simulator reads coordinates as `f64`. [`f32_positions_differ`]
//! counts the coordinates of the shared models that an `f32` reader would
//! change. `tobj` also reports errors without a line number.

use std::io::Cursor;

use sornav_platform_sim::obj::parse_obj;
use sornav_test_support::shared_data;

/// Triangles of `tobj`'s reading (all models, fan-triangulated), as
/// coordinate triples.
fn tobj_triangles(text: &str) -> Vec<[[f32; 3]; 3]> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut Cursor::new(text), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .expect("tobj reads the file");
    let mut out = Vec::new();
    for m in models {
        let p = &m.mesh.positions;
        let at = |i: u32| {
            let i = i as usize * 3;
            [p[i], p[i + 1], p[i + 2]]
        };
        for t in m.mesh.indices.chunks_exact(3) {
            out.push([at(t[0]), at(t[1]), at(t[2])]);
        }
    }
    out
}

/// Triangles of this crate's reader, rounded to `f32` as `tobj` stores them.
fn our_triangles(text: &str) -> Vec<[[f32; 3]; 3]> {
    let m = parse_obj(text, "model.obj").expect("parse_obj reads the file");
    #[allow(clippy::cast_possible_truncation)]
    let at = |i: u32| {
        let v = m.vertices[i as usize];
        [v.x as f32, v.y as f32, v.z as f32]
    };
    m.triangles
        .iter()
        .map(|t| [at(t[0]), at(t[1]), at(t[2])])
        .collect()
}

fn shared_models() -> Vec<(String, String)> {
    let Some(dir) = shared_data("sh3d-homes") else {
        return Vec::new();
    };
    let mut out: Vec<(String, String)> = std::fs::read_dir(dir.join("models"))
        .expect("models directory")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "obj"))
        .map(|p| {
            let text = std::fs::read_to_string(&p).expect("model text");
            (p.display().to_string(), text)
        })
        .collect();
    out.sort();
    out
}

#[test]
fn same_triangles_as_tobj_on_synthetic_files() {
    for text in [
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
        "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nusemtl a\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf -1 -2 -3\n",
        "o a\nv 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\ng b\nv 5 5 5\nv 6 5 5\nv 5 6 5\nv 5 5 6\nf 4//1 5//1 6//1 7//1\n",
    ] {
        assert_eq!(our_triangles(text), tobj_triangles(text), "{text}");
    }
}

#[test]
fn same_triangles_as_tobj_on_the_shared_models() {
    let models = shared_models();
    for (name, text) in &models {
        assert_eq!(our_triangles(text), tobj_triangles(text), "{name}");
    }
    eprintln!("{} shared models read alike", models.len());
}

/// The measurement behind keeping `f64` parsing: how many coordinates of
/// the shared models an `f32` reader changes (printed; the test fails only
/// if none would, which would remove the reason).
#[test]
fn f32_positions_differ() {
    let models = shared_models();
    if models.is_empty() {
        return;
    }
    let (mut total, mut changed) = (0usize, 0usize);
    for (name, text) in &models {
        let m = parse_obj(text, name).expect("parse_obj reads the file");
        for v in &m.vertices {
            for c in [v.x, v.y, v.z] {
                total += 1;
                #[allow(clippy::cast_possible_truncation)]
                let rounded = f64::from(c as f32);
                changed += usize::from(rounded != c);
            }
        }
    }
    eprintln!("{changed} of {total} coordinates change when read as f32");
    assert!(changed > 0);
}
