//! Scene validation, JSON round trips, and the checked-in scene files under `reference/scenes`.
//!
//! Every validation test starts from a valid suite scene, breaks exactly one field, and checks
//! that `validate()` rejects it with an error naming that field.

use glam::DVec3;
use scatter_reference::scene::{Light, Orientation, Scene, SceneError, Shape};
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use std::path::PathBuf;

fn sphere() -> Scene {
    suite::scene(
        SceneName::Sphere,
        Pose::Ordinary,
        MediumPreset::Default,
        32,
        18,
    )
}

fn spot() -> Scene {
    suite::scene(
        SceneName::SpotGrate,
        Pose::Ordinary,
        MediumPreset::Default,
        32,
        18,
    )
}

/// Asserts that `scene` is rejected as invalid with `field` as the offending field, and that
/// the message names it.
#[track_caller]
fn assert_invalid(scene: &Scene, field: &str) {
    match scene.validate() {
        Ok(()) => panic!("scene with a broken {field} validated"),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.contains(field), "message {msg:?} does not name {field}");
            match e {
                SceneError::Invalid { field: f, problem } => {
                    assert_eq!(f, field, "wrong field reported ({problem})");
                    assert!(!problem.is_empty());
                }
                other => panic!("expected SceneError::Invalid, got {other:?}"),
            }
        }
    }
}

/// Applies `f` to a fresh copy of `base` and asserts the result is invalid in `field`.
#[track_caller]
fn breaks(base: &Scene, field: &str, f: impl FnOnce(&mut Scene)) {
    let mut s = base.clone();
    f(&mut s);
    assert_invalid(&s, field);
}

#[test]
fn base_scenes_are_valid() {
    sphere().validate().unwrap();
    spot().validate().unwrap();
    assert!(matches!(sphere().light, Light::Directional { .. }));
    assert!(matches!(spot().light, Light::Spot { .. }));
    assert!(matches!(sphere().geometry[1], Shape::Sphere { .. }));
    assert!(matches!(spot().geometry[1], Shape::Box { .. }));
}

// ---------------------------------------------------------------------------------------------
// camera

#[test]
fn camera_position_must_be_finite() {
    breaks(&sphere(), "camera.position.x", |s| {
        s.camera.position.x = f64::NAN;
    });
    breaks(&sphere(), "camera.position.y", |s| {
        s.camera.position.y = f64::INFINITY;
    });
    breaks(&sphere(), "camera.position.z", |s| {
        s.camera.position.z = f64::NEG_INFINITY;
    });
}

#[test]
fn camera_orientation_must_be_well_defined() {
    // Zero-length forward.
    breaks(&sphere(), "camera.orientation.forward", |s| {
        s.camera.orientation = Orientation::Forward {
            forward: DVec3::ZERO,
            up: DVec3::Y,
        };
    });
    // Look-at target == position.
    breaks(&sphere(), "camera.orientation.(target - position)", |s| {
        s.camera.orientation = Orientation::LookAt {
            target: s.camera.position,
            up: DVec3::Y,
        };
    });
    // NaN target.
    breaks(&sphere(), "camera.orientation.target.z", |s| {
        s.camera.orientation = Orientation::LookAt {
            target: DVec3::new(0.0, 0.0, f64::NAN),
            up: DVec3::Y,
        };
    });
    // Zero-length up.
    breaks(&sphere(), "camera.orientation.up", |s| {
        s.camera.orientation = Orientation::LookAt {
            target: DVec3::ZERO,
            up: DVec3::ZERO,
        };
    });
}

#[test]
fn camera_up_must_not_be_parallel_to_view() {
    // Looking straight up, with up = +y.
    breaks(&sphere(), "camera.orientation.up", |s| {
        s.camera.orientation = Orientation::LookAt {
            target: s.camera.position + DVec3::new(0.0, 5.0, 0.0),
            up: DVec3::Y,
        };
    });
    // Looking straight down (anti-parallel), scaled up vector.
    breaks(&sphere(), "camera.orientation.up", |s| {
        s.camera.orientation = Orientation::Forward {
            forward: DVec3::new(0.0, -2.0, 0.0),
            up: DVec3::new(0.0, 7.0, 0.0),
        };
    });
    // A valid forward orientation is accepted.
    let mut s = sphere();
    s.camera.orientation = Orientation::Forward {
        forward: DVec3::new(0.0, -1.0, -3.0),
        up: DVec3::Y,
    };
    s.validate().unwrap();
}

#[test]
fn camera_fov_must_be_in_open_range() {
    for fov in [0.0, 180.0, f64::NAN, -10.0, 200.0, f64::INFINITY] {
        breaks(&sphere(), "camera.fov_y_deg", |s| s.camera.fov_y_deg = fov);
    }
    for fov in [0.5, 179.5] {
        let mut s = sphere();
        s.camera.fov_y_deg = fov;
        s.validate().unwrap();
    }
}

#[test]
fn camera_near_and_far() {
    breaks(&sphere(), "camera.far", |s| s.camera.far = s.camera.near);
    breaks(&sphere(), "camera.far", |s| {
        s.camera.near = 10.0;
        s.camera.far = 5.0;
    });
    breaks(&sphere(), "camera.far", |s| s.camera.far = f64::NAN);
    breaks(&sphere(), "camera.near", |s| s.camera.near = 0.0);
    breaks(&sphere(), "camera.near", |s| s.camera.near = -0.1);
    breaks(&sphere(), "camera.near", |s| s.camera.near = f64::NAN);
}

#[test]
fn camera_size_must_be_nonzero() {
    breaks(&sphere(), "camera.width/height", |s| s.camera.width = 0);
    breaks(&sphere(), "camera.width/height", |s| s.camera.height = 0);
    let mut s = sphere();
    s.camera.width = 1;
    s.camera.height = 1;
    s.validate().unwrap();
}

// ---------------------------------------------------------------------------------------------
// light

#[test]
fn directional_light_fields() {
    breaks(&sphere(), "light.direction", |s| {
        s.light = Light::Directional {
            direction: DVec3::ZERO,
            irradiance: [1.0; 3],
        };
    });
    breaks(&sphere(), "light.direction.y", |s| {
        s.light = Light::Directional {
            direction: DVec3::new(0.0, f64::NAN, 0.0),
            irradiance: [1.0; 3],
        };
    });
    breaks(&sphere(), "light.irradiance.g", |s| {
        s.light = Light::Directional {
            direction: -DVec3::Y,
            irradiance: [1.0, -0.5, 1.0],
        };
    });
    breaks(&sphere(), "light.irradiance.b", |s| {
        s.light = Light::Directional {
            direction: -DVec3::Y,
            irradiance: [1.0, 1.0, f64::INFINITY],
        };
    });
}

/// Replaces fields of the spot light of `s`.
fn edit_spot(
    s: &mut Scene,
    f: impl FnOnce(&mut DVec3, &mut DVec3, &mut f64, &mut f64, &mut [f64; 3]),
) {
    match &mut s.light {
        Light::Spot {
            position,
            direction,
            inner_angle_deg,
            outer_angle_deg,
            intensity,
            ..
        } => f(
            position,
            direction,
            inner_angle_deg,
            outer_angle_deg,
            intensity,
        ),
        other => panic!("expected a spot light, got {other:?}"),
    }
}

#[test]
fn spot_light_fields() {
    let base = spot();
    breaks(&base, "light.direction", |s| {
        edit_spot(s, |_, d, _, _, _| *d = DVec3::ZERO);
    });
    breaks(&base, "light.position.x", |s| {
        edit_spot(s, |p, _, _, _, _| p.x = f64::NAN);
    });
    // inner > outer
    breaks(&base, "light.inner_angle_deg", |s| {
        edit_spot(s, |_, _, i, o, _| {
            *i = 40.0;
            *o = 30.0;
        });
    });
    breaks(&base, "light.inner_angle_deg", |s| {
        edit_spot(s, |_, _, i, _, _| *i = -1.0);
    });
    // outer 0 or > 180
    breaks(&base, "light.outer_angle_deg", |s| {
        edit_spot(s, |_, _, i, o, _| {
            *i = 0.0;
            *o = 0.0;
        });
    });
    breaks(&base, "light.outer_angle_deg", |s| {
        edit_spot(s, |_, _, _, o, _| *o = 181.0);
    });
    breaks(&base, "light.outer_angle_deg", |s| {
        edit_spot(s, |_, _, _, o, _| *o = f64::NAN);
    });
    breaks(&base, "light.intensity.r", |s| {
        edit_spot(s, |_, _, _, _, c| c[0] = -1.0);
    });
    // Boundaries that are allowed: inner == outer, and outer == 180 (a point light).
    let mut s = base.clone();
    edit_spot(&mut s, |_, _, i, o, _| {
        *i = 30.0;
        *o = 30.0;
    });
    s.validate().unwrap();
    let mut s = base;
    edit_spot(&mut s, |_, _, i, o, _| {
        *i = 0.0;
        *o = 180.0;
    });
    s.validate().unwrap();
}

// ---------------------------------------------------------------------------------------------
// medium and sky

#[test]
fn medium_fields() {
    breaks(&sphere(), "medium.sigma_t", |s| s.medium.sigma_t = -0.01);
    breaks(&sphere(), "medium.sigma_t", |s| s.medium.sigma_t = f64::NAN);
    breaks(&sphere(), "medium.albedo", |s| s.medium.albedo = 1.5);
    breaks(&sphere(), "medium.albedo", |s| s.medium.albedo = -0.1);
    breaks(&sphere(), "medium.g", |s| s.medium.g = 1.0);
    breaks(&sphere(), "medium.g", |s| s.medium.g = -1.0);
    breaks(&sphere(), "medium.g", |s| s.medium.g = f64::NAN);
    // Boundaries that are allowed: no medium at all, albedo 0 and 1, g just inside (-1, 1).
    for (sigma_t, albedo, g) in [(0.0, 0.0, 0.0), (1.0, 1.0, 0.999), (0.1, 0.5, -0.999)] {
        let mut s = sphere();
        s.medium.sigma_t = sigma_t;
        s.medium.albedo = albedo;
        s.medium.g = g;
        s.validate().unwrap();
    }
}

#[test]
fn sky_must_be_nonnegative() {
    breaks(&sphere(), "sky.r", |s| s.sky[0] = -1.0);
    breaks(&sphere(), "sky.b", |s| s.sky[2] = f64::NAN);
}

// ---------------------------------------------------------------------------------------------
// geometry

#[test]
fn sphere_radius_must_be_positive() {
    let set_radius = |r: f64| {
        move |s: &mut Scene| match &mut s.geometry[1] {
            Shape::Sphere { radius, .. } => *radius = r,
            other => panic!("expected a sphere, got {other:?}"),
        }
    };
    breaks(&sphere(), "geometry[1].radius", set_radius(0.0));
    breaks(&sphere(), "geometry[1].radius", set_radius(-2.0));
    breaks(&sphere(), "geometry[1].radius", set_radius(f64::NAN));
    breaks(&sphere(), "geometry[1].center.y", |s| {
        match &mut s.geometry[1] {
            Shape::Sphere { center, .. } => center.y = f64::INFINITY,
            other => panic!("expected a sphere, got {other:?}"),
        }
    });
}

#[test]
fn shape_albedo_must_be_nonnegative() {
    breaks(&sphere(), "geometry[1].albedo.g", |s| {
        match &mut s.geometry[1] {
            Shape::Sphere { albedo, .. } => albedo[1] = -0.2,
            other => panic!("expected a sphere, got {other:?}"),
        }
    });
}

#[test]
fn plane_normal_must_be_nonzero() {
    breaks(&sphere(), "geometry[0].normal", |s| {
        match &mut s.geometry[0] {
            Shape::Plane { normal, .. } => *normal = DVec3::ZERO,
            other => panic!("expected a plane, got {other:?}"),
        }
    });
}

#[test]
fn box_max_must_exceed_min() {
    let edit = |f: fn(&mut DVec3, &mut DVec3)| {
        move |s: &mut Scene| match &mut s.geometry[1] {
            Shape::Box { min, max, .. } => f(min, max),
            other => panic!("expected a box, got {other:?}"),
        }
    };
    // Equal in one component (a flat box), smaller in one, swapped entirely.
    breaks(&spot(), "geometry[1].max", edit(|min, max| max.y = min.y));
    breaks(
        &spot(),
        "geometry[1].max",
        edit(|min, max| max.z = min.z - 1.0),
    );
    breaks(&spot(), "geometry[1].max", edit(std::mem::swap));
    breaks(
        &spot(),
        "geometry[1].min.x",
        edit(|min, _| min.x = f64::NAN),
    );
}

#[test]
fn cylinder_fields() {
    let base = suite::scene(
        SceneName::Columns,
        Pose::Ordinary,
        MediumPreset::Default,
        32,
        18,
    );
    base.validate().unwrap();
    let edit = |f: fn(&mut DVec3, &mut DVec3, &mut f64)| {
        move |s: &mut Scene| match &mut s.geometry[1] {
            Shape::Cylinder { a, b, radius, .. } => f(a, b, radius),
            other => panic!("expected a cylinder, got {other:?}"),
        }
    };
    breaks(&base, "geometry[1].(b - a)", edit(|a, b, _| *b = *a));
    breaks(&base, "geometry[1].radius", edit(|_, _, r| *r = 0.0));
}

#[test]
fn heightfield_fields() {
    let base = suite::scene(
        SceneName::Terrain,
        Pose::Ordinary,
        MediumPreset::Default,
        32,
        18,
    );
    base.validate().unwrap();
    let edit = |f: fn(&mut [f64; 2], &mut [u32; 2], &mut Vec<f64>)| {
        move |s: &mut Scene| match &mut s.geometry[0] {
            Shape::Heightfield {
                size,
                samples,
                heights,
                ..
            } => f(size, samples, heights),
            other => panic!("expected a heightfield, got {other:?}"),
        }
    };
    breaks(
        &base,
        "geometry[0].heights",
        edit(|_, _, h| {
            h.pop();
        }),
    );
    breaks(&base, "geometry[0].heights", edit(|_, _, h| h.push(0.0)));
    breaks(&base, "geometry[0].heights", edit(|_, s, _| s[0] += 1));
    breaks(
        &base,
        "geometry[0].samples",
        edit(|_, s, h| {
            *s = [1, 4];
            h.truncate(4);
        }),
    );
    breaks(
        &base,
        "geometry[0].heights[5]",
        edit(|_, _, h| h[5] = f64::NAN),
    );
    breaks(&base, "geometry[0].size[1]", edit(|sz, _, _| sz[1] = 0.0));
}

#[test]
fn mesh_indices_must_be_in_range() {
    let mesh = |triangles: Vec<[u32; 3]>| Shape::Mesh {
        vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
        triangles,
        albedo: [0.5; 3],
    };
    let mut ok = sphere();
    ok.geometry.push(mesh(vec![[0, 1, 2], [1, 2, 3]]));
    ok.validate().unwrap();
    assert_eq!(ok.occluder_count(), 4);
    breaks(&sphere(), "geometry[2].triangles[1]", |s| {
        s.geometry.push(mesh(vec![[0, 1, 2], [1, 4, 3]]));
    });
    breaks(&sphere(), "geometry[2].triangles[0]", |s| {
        s.geometry.push(mesh(vec![[u32::MAX, 1, 2]]));
    });
    breaks(&sphere(), "geometry[2].vertices[0].x", |s| {
        s.geometry.push(Shape::Mesh {
            vertices: vec![DVec3::new(f64::NAN, 0.0, 0.0), DVec3::X, DVec3::Y],
            triangles: vec![[0, 1, 2]],
            albedo: [0.5; 3],
        });
    });
}

#[test]
fn first_offending_field_is_reported() {
    // Camera is checked before the medium, the medium before geometry.
    breaks(&sphere(), "camera.fov_y_deg", |s| {
        s.camera.fov_y_deg = 0.0;
        s.medium.g = 2.0;
        s.geometry.clear();
    });
    breaks(&sphere(), "medium.g", |s| {
        s.medium.g = 2.0;
        if let Shape::Sphere { radius, .. } = &mut s.geometry[1] {
            *radius = -1.0;
        }
    });
}

// ---------------------------------------------------------------------------------------------
// the suite

fn all_suite_scenes(w: u32, h: u32) -> impl Iterator<Item = Scene> {
    SceneName::ALL.iter().flat_map(move |&n| {
        Pose::ALL.iter().flat_map(move |&p| {
            MediumPreset::ALL
                .iter()
                .map(move |&m| suite::scene(n, p, m, w, h))
        })
    })
}

#[test]
fn every_suite_scene_validates() {
    let mut count = 0;
    for s in all_suite_scenes(suite::DEFAULT_SIZE.0, suite::DEFAULT_SIZE.1) {
        if let Err(e) = s.validate() {
            panic!("suite scene {} is invalid: {e}", s.name);
        }
        count += 1;
    }
    assert_eq!(count, 6 * 4 * 3);
    assert_eq!(SceneName::ALL.len(), 6);
    assert_eq!(Pose::ALL.len(), 4);
    assert_eq!(MediumPreset::ALL.len(), 3);
}

#[test]
fn suite_scene_names_are_distinct() {
    let mut names: Vec<String> = all_suite_scenes(8, 8).map(|s| s.name).collect();
    let n = names.len();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), n, "duplicate suite scene names");
}

#[test]
fn json_round_trip_every_suite_scene() {
    for s in all_suite_scenes(16, 9) {
        let text = s.to_json();
        let back = match Scene::from_json(&text) {
            Ok(b) => b,
            Err(e) => panic!("{}: from_json(to_json) failed: {e}", s.name),
        };
        assert!(back == s, "{}: JSON round trip changed the scene", s.name);
        // Serialising again is stable too.
        assert_eq!(back.to_json(), text, "{}", s.name);
    }
}

// ---------------------------------------------------------------------------------------------
// JSON and file errors

#[test]
fn malformed_json_is_an_error() {
    for text in [
        "",
        "{",
        "not json",
        "[]",
        "{\"name\": \"x\"}",
        "{\"name\": 3}",
    ] {
        match Scene::from_json(text) {
            Err(SceneError::Json(_)) => {}
            other => panic!("{text:?}: expected a JSON error, got {other:?}"),
        }
    }
    // A truncated copy of a valid scene.
    let text = sphere().to_json();
    let cut = &text[..text.len() / 2];
    assert!(matches!(Scene::from_json(cut), Err(SceneError::Json(_))));
    // An unknown shape type.
    let bad = text.replacen("\"type\": \"sphere\"", "\"type\": \"torus\"", 1);
    assert_ne!(bad, text);
    let err = Scene::from_json(&bad).unwrap_err();
    assert!(matches!(err, SceneError::Json(_)), "{err:?}");
    assert!(err.to_string().contains("torus"), "{err}");
}

#[test]
fn json_with_invalid_value_names_the_field() {
    let text = sphere().to_json();
    let needle = "\"fov_y_deg\": 60.0";
    assert!(text.contains(needle), "unexpected JSON form:\n{text}");
    let bad = text.replacen(needle, "\"fov_y_deg\": 200", 1);
    let err = Scene::from_json(&bad).unwrap_err();
    assert!(
        matches!(&err, SceneError::Invalid { field, .. } if field == "camera.fov_y_deg"),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(msg.contains("camera.fov_y_deg"), "{msg}");
    assert!(msg.contains("200"), "{msg}");

    let bad = text.replacen("\"g\": 0.3", "\"g\": -1.0", 1);
    assert_ne!(bad, text);
    let err = Scene::from_json(&bad).unwrap_err();
    assert!(err.to_string().contains("medium.g"), "{err}");
}

#[test]
fn json_defaults_for_sky_and_albedo() {
    // `sky` and shape `albedo` may be omitted.
    let text = r#"{
        "name": "minimal",
        "camera": {
            "position": [0.0, 1.0, 5.0],
            "orientation": {"type": "look_at", "target": [0.0, 1.0, 0.0], "up": [0.0, 1.0, 0.0]},
            "fov_y_deg": 45.0, "near": 0.1, "far": 50.0, "width": 8, "height": 4
        },
        "light": {"type": "directional", "direction": [0.0, -1.0, 0.0], "irradiance": [1.0, 1.0, 1.0]},
        "medium": {"sigma_t": 0.1, "albedo": 0.5, "g": 0.0},
        "geometry": [{"type": "sphere", "center": [0.0, 1.0, 0.0], "radius": 0.5}]
    }"#;
    let s = Scene::from_json(text).unwrap();
    assert_eq!(s.sky, [0.02, 0.025, 0.035]);
    assert_eq!(s.geometry[0].albedo(), [0.6, 0.6, 0.6]);
    assert_eq!(s.camera.width, 8);
    assert_eq!(Scene::from_json(&s.to_json()).unwrap(), s);
}

#[test]
fn load_missing_file_is_io_error_naming_the_path() {
    let path = std::env::temp_dir().join(format!(
        "scatter-missing-{}-load_missing_file/no_such_scene.json",
        std::process::id()
    ));
    let err = Scene::load(&path).unwrap_err();
    let shown = path.display().to_string();
    match &err {
        SceneError::Io { path: p, source } => {
            assert_eq!(p, &shown);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected SceneError::Io, got {other:?}"),
    }
    assert!(err.to_string().contains(&shown), "{err}");
}

// ---------------------------------------------------------------------------------------------
// checked-in scene files (reference/scenes)

/// The files under `reference/scenes` and the suite scenes they hold (at 320x180).
const SCENE_FILES: &[(&str, SceneName, Pose)] = &[
    ("sphere_ordinary.json", SceneName::Sphere, Pose::Ordinary),
    (
        "columns_epipole_on_screen.json",
        SceneName::Columns,
        Pose::EpipoleOnScreen,
    ),
];

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// With `SCATTER_BLESS=1` rewrites the scene files from the suite; otherwise checks that they
/// load and equal the built-in scenes.
#[test]
fn scene_files_match_the_suite() {
    let bless = std::env::var("SCATTER_BLESS").is_ok_and(|v| v == "1");
    let (w, h) = suite::DEFAULT_SIZE;
    for &(file, name, pose) in SCENE_FILES {
        let path = scenes_dir().join(file);
        let built = suite::scene(name, pose, MediumPreset::Default, w, h);
        if bless {
            let mut text = built.to_json();
            text.push('\n');
            std::fs::write(&path, text)
                .unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
        }
        let loaded = Scene::load(&path).unwrap_or_else(|e| {
            panic!("{e}\n(regenerate the scene files with SCATTER_BLESS=1 cargo test -p scatter-reference --test scene_validation)")
        });
        assert!(
            loaded == built,
            "{} differs from suite::scene({name}, {pose}, default, {w}, {h}); if the suite \
             changed on purpose, rerun with SCATTER_BLESS=1 cargo test -p scatter-reference \
             --test scene_validation",
            path.display()
        );
    }
}

/// The example scene with a `mesh_file` entry: its OBJ (quads) loads as one triangle mesh,
/// scaled and translated, and the scene validates.
#[test]
fn mesh_file_entries_load_their_obj_as_a_triangle_mesh() {
    let scene = Scene::load(scenes_dir().join("mesh_grate.json")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.geometry.len(), 2);
    let Shape::Mesh {
        vertices,
        triangles,
        albedo,
    } = &scene.geometry[1]
    else {
        panic!("geometry[1] is {:?}", scene.geometry[1]);
    };
    // 14 bars, 8 corners and 6 quads (12 triangles) each.
    assert_eq!(vertices.len(), 14 * 8);
    assert_eq!(triangles.len(), 14 * 12);
    assert_eq!(scene.occluder_count(), 1 + 14 * 12);
    assert_eq!(*albedo, [0.35, 0.3, 0.25]);
    for v in vertices {
        assert!(
            (v.y - 5.0).abs() < 0.13 && v.x.abs() < 3.2 && v.z.abs() < 3.2,
            "{v}"
        );
    }
    // A parsed scene holds the mesh itself: it round-trips through JSON without the file.
    let back = Scene::from_json(&scene.to_json()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back, scene);
}

/// A scratch directory with `scene.json` (the `mesh_grate` scene with `entry` as its second
/// shape) and `files`; the scene loaded from it.
fn load_with_mesh_entry(
    test: &str,
    entry: serde_json::Value,
    files: &[(&str, &str)],
) -> Result<Scene, SceneError> {
    let dir = std::env::temp_dir().join(format!("scatter-scene-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let text = std::fs::read_to_string(scenes_dir().join("mesh_grate.json"))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut value: serde_json::Value =
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}"));
    value["geometry"][1] = entry;
    std::fs::write(dir.join("scene.json"), value.to_string()).unwrap_or_else(|e| panic!("{e}"));
    for (name, body) in files {
        std::fs::write(dir.join(name), body).unwrap_or_else(|e| panic!("{e}"));
    }
    let scene = Scene::load(dir.join("scene.json"));
    let _ = std::fs::remove_dir_all(&dir);
    scene
}

/// (test name, the `mesh_file` entry, files beside the scene, expected error text).
type BadMeshCase = (
    &'static str,
    serde_json::Value,
    &'static [(&'static str, &'static str)],
    &'static str,
);

/// Bad `mesh_file` entries: one error naming the field, never a panic.
#[test]
fn bad_mesh_file_entries_are_refused_naming_the_field() {
    const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    let cases: [BadMeshCase; 6] = [
        (
            "missing",
            serde_json::json!({"type": "mesh_file", "path": "nowhere.obj"}),
            &[],
            "geometry[1].path cannot load OBJ file",
        ),
        (
            "gltf",
            serde_json::json!({"type": "mesh_file", "path": "m.gltf"}),
            &[("m.gltf", "{}")],
            "geometry[1].path must name a Wavefront OBJ file",
        ),
        (
            "scale",
            serde_json::json!({"type": "mesh_file", "path": "m.obj", "scale": 0.0}),
            &[("m.obj", SQUARE)],
            "geometry[1].scale must be > 0, got 0",
        ),
        (
            "translate",
            serde_json::json!({"type": "mesh_file", "path": "m.obj", "translate": [0.0, "up", 0.0]}),
            &[("m.obj", SQUARE)],
            "geometry[1] invalid type",
        ),
        (
            "unknown",
            serde_json::json!({"type": "mesh_file", "path": "m.obj", "rotate": 90}),
            &[("m.obj", SQUARE)],
            "geometry[1] unknown field `rotate`",
        ),
        (
            "faceless",
            serde_json::json!({"type": "mesh_file", "path": "m.obj"}),
            &[("m.obj", "v 0 0 0\nv 1 0 0\n")],
            "the OBJ file has no faces",
        ),
    ];
    for (test, entry, files, expected) in cases {
        match load_with_mesh_entry(test, entry, files) {
            Ok(_) => panic!("{test}: accepted"),
            Err(e) => {
                let e = e.to_string();
                assert!(e.contains(expected), "{test}: {e}");
                assert!(!e.contains('\n'), "{test}: {e}");
            }
        }
    }
    // And a good one: the square (one quad) becomes two triangles, scaled then moved.
    let scene = load_with_mesh_entry(
        "square",
        serde_json::json!({"type": "mesh_file", "path": "m.obj", "scale": 2.0, "translate": [0.0, 1.0, 0.0]}),
        &[("m.obj", SQUARE)],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let Shape::Mesh {
        vertices,
        triangles,
        ..
    } = &scene.geometry[1]
    else {
        panic!("{:?}", scene.geometry[1]);
    };
    assert_eq!(triangles.len(), 2);
    assert_eq!(vertices[2], DVec3::new(2.0, 3.0, 0.0));
}

/// `scene` with `cookie` on its spot light.
fn with_cookie(scene: &Scene, cookie: Option<scatter_reference::cookie::Cookie>) -> Scene {
    let mut s = scene.clone();
    match &mut s.light {
        Light::Spot { cookie: c, .. } => *c = cookie,
        Light::Directional { .. } | Light::Area(_) => panic!("a cookie needs a spot light"),
    }
    s
}

/// The example scene with a cookie (`stained_glass.json`): the `spot_grate` suite scene at
/// `ordinary` with the `stained_glass` pattern at 64^2, as `Scene::to_json` writes it.
#[test]
fn the_stained_glass_scene_file_is_spot_grate_with_a_cookie() {
    use scatter_reference::cookie::Cookie;
    let bless = std::env::var("SCATTER_BLESS").is_ok_and(|v| v == "1");
    let (w, h) = suite::DEFAULT_SIZE;
    let path = scenes_dir().join("stained_glass.json");
    let mut built = with_cookie(
        &suite::scene(
            SceneName::SpotGrate,
            Pose::Ordinary,
            MediumPreset::Default,
            w,
            h,
        ),
        Some(Cookie::pattern("stained_glass", 64).expect("a built-in pattern")),
    );
    built.name = "stained_glass".into();
    if bless {
        let mut text = built.to_json();
        text.push('\n');
        std::fs::write(&path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
    let loaded = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        loaded == built,
        "{} differs from spot_grate/ordinary with the stained_glass cookie (SCATTER_BLESS=1 \
         rewrites it)",
        path.display()
    );
    let cookie = loaded.light.cookie().expect("a cookie");
    assert_eq!((cookie.width(), cookie.height()), (64, 64));
}

/// A cookie read from a PNG file: sRGB decoded to linear, the path relative to the scene
/// file, 8-bit gray and RGBA; and every way a cookie entry can be wrong, refused with one line.
#[test]
fn cookie_entries_load_pngs_and_refuse_bad_input() {
    let dir = std::env::temp_dir().join(format!("scatter-cookie-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("cookies")).expect("temp dir");
    // A 2x1 RGBA PNG: sRGB (255, 128, 0) and (0, 0, 255).
    let png_path = dir.join("cookies").join("two.png");
    {
        let file = std::fs::File::create(&png_path).expect("png");
        let mut enc = png::Encoder::new(file, 2, 1);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().expect("header");
        w.write_image_data(&[255, 128, 0, 255, 0, 0, 255, 7])
            .expect("data");
    }
    let base = spot();
    let mut value: serde_json::Value = serde_json::from_str(&base.to_json()).expect("json");
    value["light"]["cookie"] = serde_json::json!({ "file": "cookies/two.png" });
    let scene_path = dir.join("scene.json");
    std::fs::write(&scene_path, value.to_string()).expect("scene");
    let loaded = Scene::load(&scene_path).unwrap_or_else(|e| panic!("{e}"));
    let cookie = loaded.light.cookie().expect("a cookie");
    assert_eq!((cookie.width(), cookie.height()), (2, 1));
    let t = cookie.texels();
    assert_eq!(t[0][0], 1.0);
    assert!((t[0][1] - 0.2158605).abs() < 1e-6, "{:?}", t[0]);
    assert_eq!(t[0][2], 0.0);
    assert_eq!(t[1], [0.0, 0.0, 1.0]);
    // Bilinear between texel centres, clamped to the edge.
    assert_eq!(cookie.sample_uv(0.0, 0.5), [1.0, f64::from(t[0][1]), 0.0]);
    let mid = cookie.sample_uv(0.5, 0.5);
    assert!(
        (mid[0] - 0.5).abs() < 1e-12 && (mid[2] - 0.5).abs() < 1e-12,
        "{mid:?}"
    );
    // From JSON text without a base directory the path is the working directory's: absent.
    let text = value.to_string();
    let err = Scene::from_json(&text).expect_err("relative to the working directory");
    assert!(err.to_string().contains("two.png"), "{err}");
    for (cookie, needle) in [
        (
            serde_json::json!({ "file": "cookies/missing.png" }),
            "missing.png",
        ),
        (
            serde_json::json!({ "file": "scene.json" }),
            "not a readable PNG",
        ),
        (serde_json::json!({ "pattern": "rose" }), "unknown pattern"),
        (
            serde_json::json!({ "pattern": "stained_glass", "size": 2 }),
            "size must be in 4..=4096",
        ),
        (
            serde_json::json!({ "file": "cookies/two.png", "pattern": "stained_glass" }),
            "exactly one of file",
        ),
        (serde_json::json!({}), "exactly one of file"),
        (
            serde_json::json!({ "file": "cookies/two.png", "size": 8 }),
            "size applies to a pattern",
        ),
        (
            serde_json::json!({ "pattern": "stained_glass", "tint": 1 }),
            "unknown field",
        ),
    ] {
        let mut v = value.clone();
        v["light"]["cookie"] = cookie.clone();
        std::fs::write(&scene_path, v.to_string()).expect("scene");
        let err = Scene::load(&scene_path).expect_err(&cookie.to_string());
        let msg = err.to_string();
        assert!(msg.contains(needle), "{cookie}: {msg}");
        assert!(!msg.contains('\n'), "{cookie}: {msg}");
    }
    // A cookie needs a cone narrower than a hemisphere.
    let mut wide = with_cookie(
        &base,
        Some(scatter_reference::cookie::Cookie::pattern("stained_glass", 8).expect("pattern")),
    );
    if let Light::Spot {
        outer_angle_deg,
        inner_angle_deg,
        ..
    } = &mut wide.light
    {
        *inner_angle_deg = 10.0;
        *outer_angle_deg = 120.0;
    }
    assert_invalid(&wide, "light.cookie");
    std::fs::remove_dir_all(&dir).ok();
}
