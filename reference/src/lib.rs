//! The CPU side of scatter: everything the GPU kernels are measured against.
//!
//! - [`scene`]: the serde scene description (camera, light, medium, geometry) with validation;
//! - [`suite`]: the named scene suite (`sphere`, `columns`, `window`, `foliage`, `terrain`,
//!   `spot_grate`), its camera poses and medium presets;
//! - [`area_ivsv`]: imperfect voxelized shadow volumes (Wyman & Dai 2013) for area lights on
//!   the CPU, the reference its kernels will mirror (issue 17; no kernel yet);
//! - [`area_suite`]: the suite's `columns`, `window` and `spot_grate` lit by area lights;
//! - [`stress`]: the stress configurations where methods break (issue 6);
//! - [`random_poses`]: seeded random camera and light poses on every suite scene (issue 12);
//! - [`paths`]: 60-frame camera paths and light rotations for the flicker measurements;
//! - [`geometry`] and [`bvh`]: primitives and a binned-SAH bounding volume hierarchy;
//! - [`buffers`]: the inputs every method gets: the camera depth buffer and a standard light
//!   shadow map, both produced by ray casting (standing in for an engine's rasteriser);
//! - [`model`]: the single-scattering model (phase functions, light falloff, closed forms);
//! - [`truth`]: the two ground truths, `exact` and `shadow_map`, accumulated in f64;
//! - [`metrics`]: error metrics between images and over image sequences;
//! - [`image`]: float images, PFM and PNG output, tone mapping and composites;
//! - [`kernels`]: a line-comparable CPU mirror of every GPU kernel;
//! - [`partial_sum_tree`]: the partial-sum-tree method (Baran et al. 2010) on the CPU, the
//!   reference its kernels will mirror (issue 15; no kernel yet).
//!
//! Conventions (used everywhere in the workspace): right-handed world, `+y` up, lengths in
//! metres, `sigma_t` in 1/m. A directional light's `direction` is the direction the light
//! *travels* (from the sun into the scene).

pub mod area_ivsv;
pub mod area_suite;
pub mod buffers;
pub mod bvh;
pub mod cookie;
pub mod desc;
pub mod geometry;
pub mod image;
pub mod kernels;
pub mod metrics;
pub mod model;
pub mod partial_sum_tree;
pub mod paths;
pub mod projective;
pub mod random_poses;
pub mod scene;
pub mod stress;
pub mod suite;
pub mod truth;
