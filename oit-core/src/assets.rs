//! The real meshes oit ships: the Stanford bunny and armadillo, embedded in the library as
//! gzip-compressed OBJ text (`oit-core/assets/`, whose README names their sources and terms), so
//! `--scene bunny` and `grid:4x4:armadillo` work from any directory, after `cargo install`, and in
//! a packaged crate.
//!
//! The embedded text is the original files' bytes (`gunzip` gives them back), read by the same
//! parser as a file ([`crate::parse_obj`]), so the triangles, and every fragment count measured on
//! the files, are the same.

use std::io::Read;
use std::path::Path;

use crate::{OitError, Scene};

/// One built-in mesh: its name, what it is, and its compressed OBJ text.
#[derive(Debug, Clone, Copy)]
pub struct BuiltinMesh {
    /// The scene name that loads it (`bunny`).
    pub name: &'static str,
    /// Its triangle count, for messages and checks.
    pub triangles: u64,
    /// Where it comes from, in a few words.
    pub source: &'static str,
    /// The gzip-compressed OBJ text.
    gz: &'static [u8],
}

/// The built-in meshes, by name.
pub const BUILTIN_MESHES: &[BuiltinMesh] = &[
    BuiltinMesh {
        name: "bunny",
        triangles: 69_666,
        source: "the Stanford bunny (Stanford 3D Scanning Repository), as Debian's glmark2-data ships it",
        gz: include_bytes!("../assets/bunny.obj.gz"),
    },
    BuiltinMesh {
        name: "armadillo",
        triangles: 52_000,
        source: "the Stanford armadillo (Stanford 3D Scanning Repository), as CGAL's example data ships it",
        gz: include_bytes!("../assets/armadillo.obj.gz"),
    },
];

impl BuiltinMesh {
    /// The mesh named `name`, if it is a built-in one.
    pub fn find(name: &str) -> Option<&'static BuiltinMesh> {
        BUILTIN_MESHES.iter().find(|m| m.name == name)
    }

    /// The OBJ text, decompressed: the original file's bytes.
    pub fn obj_text(&self) -> Result<String, OitError> {
        let mut text = String::with_capacity(self.gz.len() * 4);
        flate2::read::GzDecoder::new(self.gz).read_to_string(&mut text).map_err(|e| OitError::Obj {
            path: format!("{}.obj.gz (built in)", self.name).into(),
            line: None,
            message: format!("cannot decompress the built-in mesh: {e}"),
        })?;
        Ok(text)
    }

    /// The mesh as a scene named after it, parsed as [`crate::load_obj`] parses a file.
    pub fn scene(&self) -> Result<Scene, OitError> {
        crate::parse_obj(Path::new(&format!("{}.obj", self.name)), &self.obj_text()?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The embedded meshes have the triangle counts of the files the committed results were
    /// measured on (the bunny's 69,666, the armadillo's 52,000), and their names.
    /// Fails if an asset is swapped or truncated, or `triangles` is edited.
    #[test]
    fn builtin_meshes_load_with_their_triangle_counts() {
        for mesh in BUILTIN_MESHES {
            let scene = mesh.scene().unwrap();
            assert_eq!(scene.name, mesh.name);
            assert_eq!(scene.triangle_count(), mesh.triangles, "{}", mesh.name);
            assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        }
    }

    /// The decompressed text is the source file's, byte for byte: FNV-1a of each, taken of the
    /// original `bunny.obj` and `armadillo.obj` when they were added (sha256 in the assets README).
    /// Fails if an asset is re-encoded in any way that changes a byte (rounded coordinates,
    /// reordered faces, stripped comments).
    #[test]
    fn builtin_meshes_are_the_original_bytes() {
        fn fnv1a(bytes: &[u8]) -> u64 {
            bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
        }
        for (name, len, hash) in EXPECTED {
            let text = BuiltinMesh::find(name).unwrap().obj_text().unwrap();
            assert_eq!((text.len(), fnv1a(text.as_bytes())), (*len, *hash), "{name}");
        }
    }

    const EXPECTED: &[(&str, usize, u64)] =
        &[("bunny", 2_397_075, 0x5f8f_59ce_fea1_eb70), ("armadillo", 1_674_981, 0xd354_7809_12a5_a581)];
}
