//! OBJ loading with tobj: several objects per file, faces triangulated, missing normals computed,
//! vertex colours (`v x y z r g b`) kept.

use std::path::Path;

use glam::{Vec3, Vec4};

use crate::{Mesh, OitError, Scene};

/// The colour OBJ objects get (linear, straight alpha): a light blue glass.
pub const OBJ_COLOR: Vec4 = Vec4::new(0.35, 0.6, 0.95, 0.35);

/// Loads every object of an OBJ file as one mesh and one instance each.
///
/// Errors name the file, and the line for malformed or non-finite vertices (tobj itself reports no
/// lines, so vertex lines are checked here first).
pub fn load_obj(path: &Path) -> Result<Scene, OitError> {
    let text =
        std::fs::read_to_string(path).map_err(|source| OitError::Io { path: path.to_path_buf(), source })?;
    let obj_err =
        |line: Option<usize>, message: String| OitError::Obj { path: path.to_path_buf(), line, message };
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        let values: Vec<&str> = words.collect();
        if values.len() < 3 {
            return Err(obj_err(Some(i + 1), format!("vertex needs at least 3 coordinates: '{line}'")));
        }
        for v in &values {
            match v.parse::<f32>() {
                Ok(x) if x.is_finite() => {}
                Ok(_) => {
                    return Err(obj_err(
                        Some(i + 1),
                        format!("vertex has a NaN or infinite value: '{line}'"),
                    ));
                }
                Err(_) => return Err(obj_err(Some(i + 1), format!("'{v}' is not a number: '{line}'"))),
            }
        }
    }
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let mut reader = std::io::BufReader::new(text.as_bytes());
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| Ok(Default::default()))
        .map_err(|e| obj_err(None, e.to_string()))?;
    let mut meshes = Vec::new();
    for (i, model) in models.into_iter().enumerate() {
        let m = model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        let to_vec3 = |v: &[f32]| v.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>();
        let positions = to_vec3(&m.positions);
        if let Some(&bad) = m.indices.iter().find(|&&ix| ix as usize >= positions.len()) {
            return Err(obj_err(None, format!("a face refers to vertex {} of {}", bad + 1, positions.len())));
        }
        let indices: Vec<[u32; 3]> = m.indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let name = if model.name.is_empty() { format!("object {}", i + 1) } else { model.name };
        let mut mesh = Mesh::new(name, positions, indices);
        if m.normals.len() == m.positions.len() {
            let normals = to_vec3(&m.normals);
            if normals.iter().all(|n| n.is_finite() && n.length_squared() > 0.0) {
                mesh.normals = normals.into_iter().map(|n| n.normalize()).collect();
            }
        }
        if m.vertex_color.len() == m.positions.len() {
            mesh.colors = Some(to_vec3(&m.vertex_color));
        }
        meshes.push(mesh);
    }
    if meshes.is_empty() {
        return Err(obj_err(None, "no faces".into()));
    }
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let scene = Scene::from_meshes(name, meshes, OBJ_COLOR);
    scene.validate().map_err(|e| obj_err(None, e.to_string()))?;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("oit-obj-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn loads_objects_quads_and_colors() {
        let p = write(
            "two.obj",
            "o a\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\nf 1 2 3 4\no b\nv 0 0 1 1 0 0\nv 1 0 1 0 1 0\nv 1 1 1 0 0 1\nv 0 1 1 1 1 1\nf 5 6 7\n",
        );
        let s = load_obj(&p).unwrap();
        assert_eq!(s.meshes.len(), 2);
        assert_eq!(s.meshes[0].indices.len(), 2, "quad triangulated");
        assert_eq!(s.meshes[1].indices.len(), 1);
        assert!(s.meshes[0].colors.is_some());
        assert!(s.meshes[0].normals.iter().all(|n| (n.z.abs() - 1.0).abs() < 1e-6), "normals computed");
    }

    #[test]
    fn errors_name_file_and_line() {
        let p = write("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
        let e = load_obj(&p).unwrap_err().to_string();
        assert!(e.contains("nan.obj") && e.contains("line 2"), "{e}");
        let p = write("junk.obj", "v 0 0 zero\n");
        assert!(load_obj(&p).unwrap_err().to_string().contains("line 1"));
        let p = write("empty.obj", "# nothing\n");
        assert!(load_obj(&p).unwrap_err().to_string().contains("empty.obj"));
        let missing = std::env::temp_dir().join("definitely-missing-oit.obj");
        assert!(load_obj(&missing).unwrap_err().to_string().contains("definitely-missing-oit.obj"));
        let p = write("badidx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
        assert!(load_obj(&p).is_err());
    }
}
