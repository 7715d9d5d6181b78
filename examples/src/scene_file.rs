//! `--scene-file PATH` of `godrays`, `bench` and `tune`: a scene of one's own (the JSON of
//! `reference/scenes/README.md`, OBJ meshes included), loaded and validated, with its
//! triangle count and BVH build time reported.

use std::path::Path;
use std::time::{Duration, Instant};

use scatter_reference::bvh::Bvh;
use scatter_reference::scene::{Scene, Shape};

/// A loaded scene file and what loading it cost.
#[derive(Debug)]
pub struct LoadedScene {
    /// The validated scene (its camera size as the file gives it).
    pub scene: Scene,
    /// Reading and parsing the file and its meshes.
    pub load: Duration,
    /// Building the BVH over its geometry once.
    pub bvh_build: Duration,
    /// Bounded primitives in that BVH (triangles count one each; planes are not in it).
    pub primitives: usize,
}

impl LoadedScene {
    /// Triangles of the scene's meshes and heightfields.
    pub fn triangles(&self) -> usize {
        self.scene
            .geometry
            .iter()
            .filter(|s| matches!(s, Shape::Mesh { .. } | Shape::Heightfield { .. }))
            .map(Shape::occluder_count)
            .sum()
    }

    /// One line: name, shapes, triangles, load and BVH build times.
    pub fn report(&self, path: &Path) -> String {
        format!(
            "{} ({}): {} shapes, {} triangles; loaded in {:.1} ms, BVH over {} primitives built in {:.1} ms",
            self.scene.name,
            path.display(),
            self.scene.geometry.len(),
            self.triangles(),
            self.load.as_secs_f64() * 1e3,
            self.primitives,
            self.bvh_build.as_secs_f64() * 1e3,
        )
    }
}

/// Loads and validates `path`; `screen` replaces the camera's width and height when given.
/// The error is one line naming the file and the offending field.
///
/// # Errors
///
/// The file cannot be read, is not a valid scene, or a mesh it names cannot be loaded.
pub fn load(path: &Path, screen: Option<[u32; 2]>) -> Result<LoadedScene, String> {
    let start = Instant::now();
    let mut scene =
        Scene::load(path).map_err(|e| format!("--scene-file {}: {e}", path.display()))?;
    if let Some([w, h]) = screen {
        scene.camera.width = w;
        scene.camera.height = h;
        scene
            .validate()
            .map_err(|e| format!("--scene-file {}: {e}", path.display()))?;
    }
    let load = start.elapsed();
    let start = Instant::now();
    let bvh = Bvh::build(&scene.geometry);
    let bvh_build = start.elapsed();
    Ok(LoadedScene {
        primitives: bvh.prim_count(),
        scene,
        load,
        bvh_build,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../reference/scenes/mesh_grate.json")
    }

    #[test]
    fn the_example_scene_file_loads_with_its_mesh() {
        let loaded = load(&example(), Some([64, 36])).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(loaded.triangles(), 168);
        assert_eq!(
            loaded.primitives, 168,
            "the triangles (the ground plane is unbounded)"
        );
        assert_eq!(
            [loaded.scene.camera.width, loaded.scene.camera.height],
            [64, 36]
        );
        let line = loaded.report(&example());
        assert!(line.starts_with("mesh_grate ("), "{line}");
        assert!(line.contains("168 triangles"), "{line}");
    }

    #[test]
    fn a_missing_file_is_one_line_naming_it() {
        let e = load(Path::new("no/such/scene.json"), None).unwrap_err();
        assert!(
            e.starts_with("--scene-file no/such/scene.json: cannot read scene file"),
            "{e}"
        );
        assert!(!e.contains('\n'), "{e}");
    }
}
