//! Writes the scene set (`particles`, `foliage`, `glass`, `cad`) as built by
//! `oit_core::scene_set::generate`, gzip-compressed GLB files, into a folder:
//!
//! ```text
//! cargo run --release -p oit-core --example scene_set -- oit-core/assets/scenes
//! ```
//!
//! With `--glb`, writes the uncompressed `.glb` files too (for a glTF viewer). The library embeds
//! the committed `.glb.gz` files; rebuild it after regenerating them.

use std::path::PathBuf;

use oit_core::scene_set::{SCENE_SET, generate, gzip};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut dir = None;
    let mut plain = false;
    for arg in std::env::args().skip(1) {
        match arg.as_str() {
            "--glb" => plain = true,
            "-h" | "--help" => {
                println!("usage: scene_set [--glb] FOLDER");
                return Ok(());
            }
            _ if dir.is_none() => dir = Some(PathBuf::from(arg)),
            _ => return Err(format!("unexpected argument '{arg}': usage: scene_set [--glb] FOLDER").into()),
        }
    }
    let dir = dir.ok_or("usage: scene_set [--glb] FOLDER")?;
    std::fs::create_dir_all(&dir)?;
    for entry in SCENE_SET {
        let scene = generate(entry.name).expect("every name of the set is generated")?;
        let glb = oit_core::write_glb(&scene)?;
        let gz = gzip(&glb);
        let path = dir.join(entry.file_name());
        std::fs::write(&path, &gz)?;
        println!(
            "{}: {} triangles, {} instances, {} textures; {} B as GLB, {} B compressed",
            path.display(),
            scene.triangle_count(),
            scene.instances.len(),
            scene.textures.len(),
            glb.len(),
            gz.len()
        );
        if plain {
            std::fs::write(dir.join(format!("{}.glb", entry.name)), &glb)?;
        }
    }
    Ok(())
}
