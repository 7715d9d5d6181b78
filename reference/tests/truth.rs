//! The ground truths against closed forms, and their quadrature convergence on the suite.

use glam::DVec3;
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::metrics;
use scatter_reference::model::{
    self, cone_falloff, directional_unshadowed, gauss_legendre_16, phase_hg, sun_airlight,
};
use scatter_reference::scene::{Camera, Light, Medium, Orientation, Scene, Shape};
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility, ray_inscatter};

fn camera(width: u32, height: u32, far: f64) -> Camera {
    Camera {
        position: DVec3::new(0.0, 1.0, 0.0),
        orientation: Orientation::Forward {
            forward: DVec3::new(1.0, 0.1, 0.3),
            up: DVec3::Y,
        },
        fov_y_deg: 60.0,
        near: 0.1,
        far,
        width,
        height,
    }
}

fn scene(light: Light, medium: Medium, geometry: Vec<Shape>) -> Scene {
    let s = Scene {
        name: "test".into(),
        camera: camera(16, 9, 50.0),
        light,
        medium,
        geometry,
        sky: [0.0; 3],
    };
    s.validate().expect("test scene is valid");
    s
}

fn sun(direction: DVec3) -> Light {
    Light::Directional {
        direction,
        irradiance: [1.0, 2.0, 3.0],
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

fn dirs() -> Vec<DVec3> {
    [
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.3, 0.8, -0.2),
        DVec3::new(-0.5, -0.1, 0.7),
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(0.2, -0.9, 0.1),
    ]
    .map(DVec3::normalize)
    .to_vec()
}

#[test]
fn unshadowed_directional_matches_closed_form() {
    let light_dir = DVec3::new(0.4, -0.7, 0.2).normalize();
    for (sigma_t, g) in [(0.05, 0.0), (0.5, 0.6), (2.0, -0.3), (1e-3, 0.9)] {
        let medium = Medium {
            sigma_t,
            albedo: 0.7,
            g,
        };
        let s = scene(sun(light_dir), medium, Vec::new());
        let bvh = Bvh::build(&s.geometry);
        for dir in dirs() {
            for len in [0.01, 1.0, 17.0, 300.0] {
                let expect = directional_unshadowed(&medium, -light_dir.dot(dir), len);
                let closed = medium.sigma_s()
                    * phase_hg(g, -light_dir.dot(dir))
                    * (1.0 - (-sigma_t * len).exp())
                    / sigma_t;
                assert!(rel(expect, closed) < 1e-12, "model helper vs formula");
                for vis in [Visibility::None, Visibility::Exact(&bvh)] {
                    let got =
                        ray_inscatter(&s, &vis, &TruthSettings::default(), DVec3::ZERO, dir, len);
                    assert!(
                        rel(got, expect) < 1e-6,
                        "sigma_t {sigma_t} g {g} dir {dir} s {len}: {got} vs {expect} ({vis:?})"
                    );
                }
            }
        }
    }
}

#[test]
fn unshadowed_directional_image_matches_closed_form_per_pixel() {
    let medium = Medium {
        sigma_t: 0.1,
        albedo: 0.9,
        g: 0.4,
    };
    let light_dir = DVec3::new(-0.3, -0.5, 0.8).normalize();
    let s = scene(
        sun(light_dir),
        medium,
        vec![Shape::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
            albedo: [0.5; 3],
        }],
    );
    let bvh = Bvh::build(&s.geometry);
    let gbuf = GBuffer::cast(&s, &bvh);
    // The light comes from above: nothing shadows the air above the plane.
    let img = truth::render(
        &s,
        &gbuf,
        &Visibility::Exact(&bvh),
        &TruthSettings::default(),
        &|| (),
    );
    let frame = s.camera.frame();
    for y in 0..s.camera.height {
        for x in 0..s.camera.width {
            let dir = s
                .camera
                .ray_dir(&frame, f64::from(x) + 0.5, f64::from(y) + 0.5);
            let len = gbuf.ray_length[(y * s.camera.width + x) as usize];
            let l = directional_unshadowed(&medium, -light_dir.dot(dir), len);
            for (c, e) in [1.0, 2.0, 3.0].into_iter().enumerate() {
                let got = f64::from(img.get(x, y)[c]);
                assert!(
                    rel(got, e * l) < 1e-6,
                    "pixel ({x}, {y}) channel {c}: {got} vs {}",
                    e * l
                );
            }
        }
    }
}

#[test]
fn sigma_t_to_zero_tends_to_linear_without_division_by_zero() {
    let light_dir = DVec3::new(0.0, -1.0, 0.3).normalize();
    let dir = DVec3::X;
    let cos = -light_dir.dot(dir);
    for sigma_t in [1e-6, 1e-9, 1e-12, 1e-200] {
        let medium = Medium {
            sigma_t,
            albedo: 0.8,
            g: 0.2,
        };
        for len in [1.0, 100.0, 1e4] {
            let linear = medium.sigma_s() * phase_hg(0.2, cos) * len;
            let got = directional_unshadowed(&medium, cos, len);
            // (1 - exp(-x)) / x = 1 - x / 2 + ...
            let tol = sigma_t * len + 1e-12;
            assert!(
                got.is_finite() && rel(got, linear) <= tol,
                "sigma_t {sigma_t} s {len}: {got} vs {linear}"
            );
            let s = scene(sun(light_dir), medium, Vec::new());
            let q = ray_inscatter(
                &s,
                &Visibility::None,
                &TruthSettings::default(),
                DVec3::ZERO,
                dir,
                len,
            );
            assert!(q.is_finite() && rel(q, linear) <= tol);
        }
    }
    // sigma_t = 0 exactly: no scattering at all, and no NaN.
    let medium = Medium {
        sigma_t: 0.0,
        albedo: 0.8,
        g: 0.2,
    };
    assert_eq!(directional_unshadowed(&medium, cos, 10.0), 0.0);
    assert_eq!(model::transmittance_integral(0.0, 10.0), 10.0);
    assert_eq!(model::transmittance_integral_between(0.0, 2.0, 10.0), 8.0);
}

#[test]
fn sun_closed_form_matches_brute_force_quadrature() {
    // The original integral: sigma_s / (4 pi) * exp(-sigma_t (d + t)) / d^2 dt, d = |x_t - light|.
    for (sigma_t, d_l, gamma, x) in [
        (0.1, 5.0, 0.7, 20.0),
        (0.5, 2.0, 2.0, 3.0),
        (0.01, 10.0, 0.2, 50.0),
        (1.0, 1.0, 1.3, 0.5),
    ] {
        let medium = Medium {
            sigma_t,
            albedo: 0.6,
            g: 0.0,
        };
        let light = DVec3::new(d_l * f64::cos(gamma), d_l * f64::sin(gamma), 0.0);
        let f = |t: f64| {
            let d = (DVec3::new(t, 0.0, 0.0) - light).length();
            medium.sigma_s() / (4.0 * std::f64::consts::PI) * (-sigma_t * (d + t)).exp() / (d * d)
        };
        let n = 4096;
        let h = x / f64::from(n);
        let brute: f64 = (0..n)
            .map(|i| gauss_legendre_16(f, h * f64::from(i), h * f64::from(i + 1)))
            .sum();
        let closed = sun_airlight(&medium, d_l, gamma, x);
        assert!(rel(closed, brute) < 1e-9, "{closed} vs {brute}");
    }
}

#[test]
fn unshadowed_isotropic_point_light_matches_sun_closed_form() {
    let medium = Medium {
        sigma_t: 0.15,
        albedo: 0.8,
        g: 0.0,
    };
    let position = DVec3::new(2.0, 3.0, -4.0);
    let light = Light::Spot {
        position,
        direction: DVec3::NEG_Y,
        inner_angle_deg: 180.0,
        outer_angle_deg: 180.0,
        intensity: [1.0; 3],
        cookie: None,
    };
    let s = scene(light, medium, Vec::new());
    let bvh = Bvh::build(&s.geometry);
    let eye = DVec3::ZERO;
    for dir in dirs() {
        let to_light = position - eye;
        let d_l = to_light.length();
        let gamma = (to_light.dot(dir) / d_l).clamp(-1.0, 1.0).acos();
        for len in [0.5, 5.0, 30.0] {
            let closed = sun_airlight(&medium, d_l, gamma, len);
            for vis in [Visibility::None, Visibility::Exact(&bvh)] {
                let got = ray_inscatter(&s, &vis, &TruthSettings::default(), eye, dir, len);
                assert!(
                    rel(got, closed) < 1e-3,
                    "dir {dir} s {len}: {got} vs {closed}"
                );
            }
        }
    }
}

/// A view ray passing millimetres from a point light (a lamp pixel): the `1 / d^2` peak is
/// far narrower than the Gauss-Legendre pieces, and the truth integrates it in the
/// equiangular variable; against the closed form within 1e-4, lit and shadowed alike.
#[test]
fn a_ray_grazing_a_point_light_matches_the_closed_form() {
    let medium = Medium {
        sigma_t: 0.15,
        albedo: 0.8,
        g: 0.0,
    };
    let position = DVec3::new(10.0, 0.0, 0.0);
    let light = Light::Spot {
        position,
        direction: DVec3::NEG_X,
        inner_angle_deg: 180.0,
        outer_angle_deg: 180.0,
        intensity: [1.0; 3],
        cookie: None,
    };
    let s = scene(light, medium, Vec::new());
    let bvh = Bvh::build(&s.geometry);
    let eye = DVec3::ZERO;
    for h in [0.3, 2e-2, 1e-3, 1e-5] {
        let dir = DVec3::new(10.0, h, 0.0).normalize();
        let to_light = position - eye;
        let gamma = (to_light.dot(dir) / to_light.length())
            .clamp(-1.0, 1.0)
            .acos();
        for len in [9.0, 10.5, 40.0] {
            let closed = sun_airlight(&medium, to_light.length(), gamma, len);
            for vis in [Visibility::None, Visibility::Exact(&bvh)] {
                let got = ray_inscatter(&s, &vis, &TruthSettings::default(), eye, dir, len);
                assert!(
                    rel(got, closed) < 1e-4,
                    "h {h} s {len}: {got} vs {closed} ({:.2e})",
                    rel(got, closed)
                );
            }
        }
    }
}

#[test]
fn phase_function_is_normalised() {
    for g in [-0.95, -0.3, 0.0, 0.5, 0.95] {
        let n = 2000;
        let h = 2.0 / f64::from(n);
        let integral: f64 = (0..n)
            .map(|i| {
                gauss_legendre_16(
                    |mu| 2.0 * std::f64::consts::PI * phase_hg(g, mu),
                    -1.0 + h * f64::from(i),
                    -1.0 + h * f64::from(i + 1),
                )
            })
            .sum();
        assert!((integral - 1.0).abs() < 1e-9, "g {g}: {integral}");
    }
    assert!((phase_hg(0.0, 0.3) - 1.0 / (4.0 * std::f64::consts::PI)).abs() < 1e-15);
    // Forward scattering peaks when the light travels towards the eye (cos theta = 1).
    assert!(phase_hg(0.7, 1.0) > phase_hg(0.7, -1.0));
}

#[test]
fn cone_falloff_is_one_inside_zero_outside_and_monotone() {
    let (inner, outer) = (20.0f64, 30.0f64);
    assert_eq!(cone_falloff(1.0, inner, outer), 1.0);
    assert_eq!(cone_falloff(19.9f64.to_radians().cos(), inner, outer), 1.0);
    assert_eq!(cone_falloff(30.1f64.to_radians().cos(), inner, outer), 0.0);
    let mut prev = 1.0;
    for i in 0..=100 {
        let a = inner + (outer - inner) * f64::from(i) / 100.0;
        let c = cone_falloff(a.to_radians().cos(), inner, outer);
        assert!(c <= prev + 1e-15 && (0.0..=1.0).contains(&c));
        prev = c;
    }
    // No cone: a point light.
    assert_eq!(cone_falloff(-1.0, 180.0, 180.0), 1.0);
    // Hard cone.
    assert_eq!(cone_falloff(25f64.to_radians().cos(), 30.0, 30.0), 1.0);
    assert_eq!(cone_falloff(35f64.to_radians().cos(), 30.0, 30.0), 0.0);
}

/// A slab that shadows exactly the view-ray interval x in [-2, 3]: the exact truth must find
/// both transitions; the shadow-map truth must approach it as the map grows.
#[test]
fn shadowed_interval_matches_piecewise_closed_form() {
    let medium = Medium {
        sigma_t: 0.2,
        albedo: 0.5,
        g: 0.0,
    };
    let s = Scene {
        camera: Camera {
            position: DVec3::new(-10.0, 1.0, 0.0),
            orientation: Orientation::Forward {
                forward: DVec3::X,
                up: DVec3::Y,
            },
            ..camera(8, 8, 30.0)
        },
        ..scene(
            sun(DVec3::NEG_Y),
            medium,
            vec![Shape::Box {
                min: DVec3::new(-2.0, 5.0, -50.0),
                max: DVec3::new(3.0, 6.0, 50.0),
                albedo: [0.5; 3],
            }],
        )
    };
    s.validate().unwrap();
    let bvh = Bvh::build(&s.geometry);
    let (eye, dir, len) = (s.camera.position, DVec3::X, 20.0);
    let c = medium.sigma_s() * phase_hg(0.0, 0.0);
    let expect = c
        * (model::transmittance_integral_between(0.2, 0.0, 8.0)
            + model::transmittance_integral_between(0.2, 13.0, 20.0));
    let exact = ray_inscatter(
        &s,
        &Visibility::Exact(&bvh),
        &TruthSettings::default(),
        eye,
        dir,
        len,
    );
    assert!(rel(exact, expect) < 1e-5, "exact truth {exact} vs {expect}");
    let mut prev = f64::INFINITY;
    for size in [64, 256, 1024] {
        let sm = ShadowMap::build(&s, &bvh, size).unwrap();
        let got = ray_inscatter(
            &s,
            &Visibility::ShadowMap(&sm),
            &TruthSettings::default(),
            eye,
            dir,
            len,
        );
        let e = rel(got, expect);
        assert!(
            e <= prev + 1e-12,
            "shadow-map error must not grow with the map: {e} after {prev}"
        );
        prev = e;
    }
    assert!(prev < 5e-3, "shadow-map truth at 1024: rel error {prev}");
}

/// Doubling the quadrature cells changes every suite image by far less than 0.1 % rel L1.
#[test]
fn quadrature_is_converged_on_every_suite_scene() {
    let coarse = TruthSettings::default();
    let fine = TruthSettings {
        segments: 2 * coarse.segments,
        ..coarse
    };
    let mut worst = (0.0, String::new());
    for &name in SceneName::ALL {
        for &pose in Pose::ALL {
            let s = suite::scene(name, pose, MediumPreset::Default, 96, 54);
            let bvh = Bvh::build(&s.geometry);
            let gbuf = GBuffer::cast(&s, &bvh);
            let sm = ShadowMap::build(&s, &bvh, 1024).unwrap();
            for (label, vis) in [
                ("exact", Visibility::Exact(&bvh)),
                ("shadow_map", Visibility::ShadowMap(&sm)),
            ] {
                let a = truth::render(&s, &gbuf, &vis, &coarse, &|| ());
                let b = truth::render(&s, &gbuf, &vis, &fine, &|| ());
                assert_eq!(metrics::non_finite_count(&a), 0);
                let d = metrics::rel_l1(&a, &b).unwrap();
                println!(
                    "{}::{label}: rel L1 {} vs {} cells = {:.5} %",
                    s.name,
                    coarse.segments,
                    fine.segments,
                    100.0 * d
                );
                assert!(
                    d < 1e-3,
                    "{}::{label}: doubling the cells changed rel L1 by {d}",
                    s.name
                );
                if d > worst.0 {
                    worst = (d, format!("{}::{label}", s.name));
                }
            }
        }
    }
    println!("worst: {} at {:.5} %", worst.1, 100.0 * worst.0);
}
