//! Property tests of the per-frame set-up (`prepare_frame`, `prepare_raymarch`,
//! `prepare_minmax`) and the min-max tree layout on hostile numbers: NaN, infinities, zero,
//! huge and tiny values, negative extinction, `g = ±1`, zero-length or parallel directions,
//! `near >= far`, a 0 or 180 degree field of view, zero or oversized screens, spot cones
//! with `inner > outer`.
//!
//! Each case starts from a valid frame (random camera and light orientation, random valid
//! variant and sizes) and mutates up to three fields. The properties:
//!
//! - nothing panics;
//! - an unmutated frame is accepted;
//! - an accepted frame has every uniform float and every slice-table float finite (and the
//!   projective matrices, when there are any);
//! - a rejected frame has a one-line message that names one of the mutated fields.
//!
//! Fixed RNG seeds: every run checks the same cases. The case counts are printed.

use std::cell::Cell;
use std::io::Write as _;
use std::time::Instant;

use glam::DVec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};
use scatter_frame::area_ivsv::{AreaIvsvFrame, AreaIvsvVariant, prepare_area_light};
use scatter_frame::area_light::{AreaLightDesc, AreaShapeDesc};
use scatter_frame::family::FamilyVariant;
use scatter_frame::frame::{
    CameraDesc, FrameSettings, FrameUniforms, LightDesc, MediumDesc, PrefilteredFrame, Resolutions,
    ShadowMapDesc, ShadowProjectionDesc, prepare_frame,
};
use scatter_frame::hybrid_volume::{HybridVolumeVariant, prepare_hybrid_volume};
use scatter_frame::minmax::{MinmaxVariant, level_count, prepare_minmax, tree_levels, tree_width};
use scatter_frame::partial_sum_tree::{
    FACTOR_VECS, PartialSumTreeFrame, PartialSumTreeVariant, prepare_partial_sum_tree,
};
use scatter_frame::raymarch::{RaymarchUniforms, RaymarchVariant, prepare_raymarch};
use scatter_frame::variant::{LightKind, PrefilteredVariant};

/// Cases of `prepare_frame` (prefiltered family, every variant of the grid).
const PREFILTERED_CASES: u32 = 6000;
/// Cases of `prepare_raymarch`.
const RAYMARCH_CASES: u32 = 3000;
/// Cases of `prepare_minmax`.
const MINMAX_CASES: u32 = 3000;
/// Cases of `prepare_hybrid_volume`.
const HYBRID_VOLUME_CASES: u32 = 1000;
/// Cases of `prepare_partial_sum_tree` (each factorises a 96 x 96 kernel grid).
const PST_CASES: u32 = 400;
/// Cases of `prepare_frame` on fully arbitrary numbers (no valid starting point).
const ARBITRARY_CASES: u32 = 2000;
/// Cases of the tree layout functions on arbitrary widths.
const TREE_CASES: u32 = 1000;

/// Runs `cases` cases of `test` on `strategy` with a fixed seed; panics with proptest's
/// report (the minimal failing input) on failure.
fn run<S: Strategy>(
    name: &str,
    cases: u32,
    seed: u64,
    strategy: S,
    test: impl Fn(S::Value) -> Result<(), TestCaseError>,
) {
    let config = Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 4096,
        ..Config::default()
    };
    let mut runner = TestRunner::new(config);
    let start = Instant::now();
    TALLY.with(|t| t.set([0, 0]));
    if let Err(e) = runner.run(&strategy, test) {
        panic!("{name}: {e}");
    }
    let [accepted, rejected] = TALLY.with(Cell::get);
    // Past libtest's capture (it only catches print!/eprint!): the counts show in every run.
    let _ = writeln!(
        std::io::stderr().lock(),
        "fuzz_frame::{name}: {cases} cases ({accepted} accepted, {rejected} rejected with a \
         clear error), 0 panics, {:.2} s",
        start.elapsed().as_secs_f64()
    );
}

thread_local! {
    /// Accepted and rejected cases of the running test (each test runs on its own thread).
    static TALLY: Cell<[u32; 2]> = const { Cell::new([0, 0]) };
}

fn tally(accepted: bool) {
    TALLY.with(|t| {
        let mut v = t.get();
        v[usize::from(!accepted)] += 1;
        t.set(v);
    });
}

/// Hostile and ordinary `f64`s.
fn wild_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => any::<f64>(),
        2 => -10.0..10.0f64,
        1 => -1.0e6..1.0e6f64,
        4 => prop::sample::select(vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            1e-300,
            -1e-300,
            1e-30,
            1e30,
            -1e30,
            1e300,
            -1e300,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            f64::EPSILON,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::from(f32::MAX),
            f64::from(f32::MAX) * 2.0,
            180.0,
            90.0,
            89.0,
            360.0,
            1e9,
            1e10,
        ]),
    ]
}

/// Hostile and ordinary vectors, including some in terms of the base camera (parallel to
/// its up vector or its forward axis).
fn wild_vec() -> impl Strategy<Value = WildVec> {
    prop_oneof![
        3 => (wild_f64(), wild_f64(), wild_f64()).prop_map(|(x, y, z)| WildVec::Abs([x, y, z])),
        2 => (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)
            .prop_map(|(x, y, z)| WildVec::Abs([x, y, z])),
        1 => Just(WildVec::Abs([0.0; 3])),
        1 => Just(WildVec::Abs([1e-300, 0.0, 0.0])),
        1 => Just(WildVec::Abs([1e300, -1e300, 1e300])),
        1 => Just(WildVec::Abs([f64::MAX, f64::MAX, f64::MAX])),
        1 => Just(WildVec::Abs([f64::NAN, 0.0, 0.0])),
        1 => Just(WildVec::Abs([0.0, f64::INFINITY, 0.0])),
        1 => Just(WildVec::CamUp),
        1 => Just(WildVec::CamForward),
        1 => Just(WildVec::CamBackward),
        1 => Just(WildVec::CamPosition),
        1 => wild_f64().prop_map(WildVec::CamForwardTimes),
    ]
}

/// A vector mutation: absolute, or relative to the base camera.
#[derive(Clone, Copy, Debug)]
enum WildVec {
    Abs([f64; 3]),
    CamUp,
    CamForward,
    CamBackward,
    CamPosition,
    CamForwardTimes(f64),
}

impl WildVec {
    fn get(self, cam: &CameraDesc) -> DVec3 {
        match self {
            Self::Abs(v) => DVec3::from_array(v),
            Self::CamUp => cam.up,
            Self::CamForward => cam.forward,
            Self::CamBackward => -cam.forward,
            Self::CamPosition => cam.position,
            Self::CamForwardTimes(s) => cam.position + cam.forward * s,
        }
    }
}

/// Hostile and ordinary sizes.
fn wild_u32() -> impl Strategy<Value = u32> {
    prop_oneof![
        2 => 0..80u32,
        1 => any::<u32>(),
        2 => prop::sample::select(vec![
            0,
            1,
            2,
            3,
            4,
            5,
            255,
            256,
            257,
            4096,
            4097,
            16384,
            16385,
            65535,
            65536,
            u32::MAX / 2,
            u32::MAX - 1,
            u32::MAX,
        ]),
    ]
}

/// One field of the frame set to a hostile value.
#[derive(Clone, Copy, Debug)]
enum Mutation {
    CamPosition(WildVec),
    CamForward(WildVec),
    CamRight(WildVec),
    CamUp(WildVec),
    TanHalfFov(f64),
    Near(f64),
    Far(f64),
    /// near = far * factor (near >= far when factor >= 1).
    NearFromFar(f64),
    LightDirection(WildVec),
    LightPosition(WildVec),
    InnerDeg(f64),
    OuterDeg(f64),
    LightColor(usize, f64),
    SigmaT(f64),
    Albedo(f64),
    G(f64),
    SmOrigin(WildVec),
    SmBasis(usize, WildVec),
    SmProjection([f64; 4]),
    SmPerspective(f64),
    SmNear(f64),
    SmFar(f64),
    SmBias(f64),
    SmSize(u32),
    ScreenWidth(u32),
    ScreenHeight(u32),
    RectifiedWidth(u32),
    RectifiedHeight(u32),
    EpipoleRadius(f64),
    MarchSteps(u32),
    SpotQuadrature(u32),
    ProjectiveMaxHalfAngle(f64),
    /// The other light type than the variant's.
    SwapLight,
    /// Prefiltered variants: `regions`, `bases` and `bases_per_thread` set without
    /// validation (the variant is plain data).
    Knobs(u32, u32, u32),
}

impl Mutation {
    /// Words of which a rejection that this mutation caused must name one.
    fn keywords(&self) -> &'static [&'static str] {
        match self {
            Self::CamPosition(_) => &["camera"],
            Self::CamForward(_) | Self::CamRight(_) | Self::CamUp(_) => &["camera"],
            Self::TanHalfFov(_) => &["fov"],
            Self::Near(_) | Self::Far(_) | Self::NearFromFar(_) => &["near", "far"],
            Self::LightDirection(_) => &["light direction", "light position/direction"],
            // The eye at the spot light: "the camera is at the spot light's position".
            Self::LightPosition(_) => &["light position", "spot light's position"],
            Self::InnerDeg(_) | Self::OuterDeg(_) => &["cone"],
            Self::LightColor(..) => &["light colour"],
            Self::SigmaT(_) => &["sigma_t"],
            Self::Albedo(_) => &["albedo"],
            Self::G(_) => &["medium g", "Henyey-Greenstein g"],
            Self::SmOrigin(_) => &["shadow map origin"],
            Self::SmBasis(..) => &["shadow map basis"],
            Self::SmProjection(_) | Self::SmPerspective(_) => &["shadow map projection"],
            Self::SmNear(_) | Self::SmFar(_) => &["shadow map near", "shadow map far"],
            Self::SmBias(_) => &["shadow map bias"],
            Self::SmSize(_) => &["shadow map size"],
            Self::ScreenWidth(_) => &["screen width"],
            Self::ScreenHeight(_) => &["screen height"],
            Self::RectifiedWidth(_) => &["rectified width"],
            Self::RectifiedHeight(_) => &["rectified height"],
            Self::EpipoleRadius(_) => &["epipole_radius_px"],
            Self::MarchSteps(_) => &["march steps"],
            Self::SpotQuadrature(_) => &["spot quadrature"],
            Self::ProjectiveMaxHalfAngle(_) => &["projective_max_half_angle_deg"],
            Self::SwapLight => &["but the frame has light = "],
            Self::Knobs(..) => &["regions", "bases"],
        }
    }
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let quad =
        (wild_f64(), wild_f64(), wild_f64(), wild_f64()).prop_map(|(a, b, c, d)| [a, b, c, d]);
    prop_oneof![
        wild_vec().prop_map(Mutation::CamPosition),
        wild_vec().prop_map(Mutation::CamForward),
        wild_vec().prop_map(Mutation::CamRight),
        wild_vec().prop_map(Mutation::CamUp),
        wild_f64().prop_map(Mutation::TanHalfFov),
        wild_f64().prop_map(Mutation::Near),
        wild_f64().prop_map(Mutation::Far),
        prop::sample::select(vec![1.0, 1.5, 0.999_999_999, 1e-20, 0.0])
            .prop_map(Mutation::NearFromFar),
        wild_vec().prop_map(Mutation::LightDirection),
        wild_vec().prop_map(Mutation::LightPosition),
        wild_f64().prop_map(Mutation::InnerDeg),
        wild_f64().prop_map(Mutation::OuterDeg),
        (0..3usize, wild_f64()).prop_map(|(i, v)| Mutation::LightColor(i, v)),
        wild_f64().prop_map(Mutation::SigmaT),
        wild_f64().prop_map(Mutation::Albedo),
        prop_oneof![
            wild_f64(),
            prop::sample::select(vec![1.0, -1.0, 0.999_999, -0.999_999])
        ]
        .prop_map(Mutation::G),
        wild_vec().prop_map(Mutation::SmOrigin),
        (0..3usize, wild_vec()).prop_map(|(i, v)| Mutation::SmBasis(i, v)),
        quad.prop_map(Mutation::SmProjection),
        wild_f64().prop_map(Mutation::SmPerspective),
        wild_f64().prop_map(Mutation::SmNear),
        wild_f64().prop_map(Mutation::SmFar),
        wild_f64().prop_map(Mutation::SmBias),
        wild_u32().prop_map(Mutation::SmSize),
        wild_u32().prop_map(Mutation::ScreenWidth),
        wild_u32().prop_map(Mutation::ScreenHeight),
        wild_u32().prop_map(Mutation::RectifiedWidth),
        wild_u32().prop_map(Mutation::RectifiedHeight),
        wild_f64().prop_map(Mutation::EpipoleRadius),
        wild_u32().prop_map(Mutation::MarchSteps),
        wild_u32().prop_map(Mutation::SpotQuadrature),
        wild_f64().prop_map(Mutation::ProjectiveMaxHalfAngle),
        Just(Mutation::SwapLight),
        (wild_u32(), wild_u32(), wild_u32()).prop_map(|(r, b, t)| Mutation::Knobs(r, b, t)),
    ]
}

/// One frame: a valid base plus mutations.
#[derive(Clone, Debug)]
struct Case {
    family: FamilyVariant,
    res: Resolutions,
    camera: CameraDesc,
    light: LightDesc,
    medium: MediumDesc,
    shadow: ShadowMapDesc,
    settings: FrameSettings,
    /// The mutated fields; `None` when every field is arbitrary.
    mutations: Option<Vec<Mutation>>,
}

/// A unit direction from spherical angles.
fn direction(azimuth: f64, elevation: f64) -> DVec3 {
    DVec3::new(
        elevation.cos() * azimuth.cos(),
        elevation.sin(),
        elevation.cos() * azimuth.sin(),
    )
}

/// Light-space basis with `forward` the direction the light travels.
fn light_basis(forward: DVec3) -> [DVec3; 3] {
    let f = forward.normalize();
    let helper = if f.y.abs() < 0.9 { DVec3::Y } else { DVec3::X };
    let right = f.cross(helper).normalize();
    let up = right.cross(f);
    [right, up, f]
}

/// Special light directions relative to the camera (epipole at the centre, on the border,
/// the light straight behind, grazing).
#[derive(Clone, Copy, Debug)]
enum LightAim {
    Random(f64, f64),
    TowardsEye,
    AwayFromEye,
    AlongUp,
    Random2(f64, f64),
}

#[allow(clippy::too_many_arguments, reason = "one argument per random choice")]
fn base_case(
    family: FamilyVariant,
    screen: [u32; 2],
    rectified: [u32; 2],
    sm_size: u32,
    cam_angles: (f64, f64),
    aim: LightAim,
    fov_deg: f64,
    mutations: Vec<Mutation>,
) -> Case {
    let forward = direction(cam_angles.0, cam_angles.1);
    let right = forward.cross(DVec3::Y).normalize();
    let up = right.cross(forward);
    let camera = CameraDesc {
        position: DVec3::new(0.5, 2.0, 8.0),
        forward,
        right,
        up,
        tan_half_fov_y: (0.5 * fov_deg).to_radians().tan(),
        near: 0.1,
        far: 60.0,
    };
    // Direction the light travels.
    let travel = match aim {
        LightAim::Random(a, e) | LightAim::Random2(a, e) => direction(a, e),
        LightAim::TowardsEye => -forward,
        LightAim::AwayFromEye => forward,
        LightAim::AlongUp => -up,
    };
    let (light, shadow) = match family.light() {
        LightKind::Directional => {
            let basis = light_basis(travel);
            (
                LightDesc::Directional {
                    direction: travel,
                    color: [1.0, 0.9, 0.8],
                },
                ShadowMapDesc {
                    origin: camera.position - travel * 40.0,
                    basis,
                    projection: ShadowProjectionDesc::Orthographic {
                        x0: -30.0,
                        x1: 30.0,
                        y0: -30.0,
                        y1: 30.0,
                    },
                    near: 0.0,
                    far: 80.0,
                    size: sm_size,
                    bias_texels: 1.5,
                },
            )
        }
        LightKind::Spot | LightKind::Area => {
            let position = camera.position - travel * 12.0 + DVec3::new(0.3, 0.2, -0.1);
            let axis = (camera.position + forward * 5.0 - position).normalize();
            (
                if family.light() == LightKind::Area {
                    LightDesc::Area(AreaLightDesc {
                        position,
                        direction: axis,
                        up: None,
                        shape: AreaShapeDesc::Rect {
                            width: 1.5,
                            height: 0.75,
                        },
                        inner_deg: 20.0,
                        outer_deg: 30.0,
                        radiance: [40.0, 35.0, 30.0],
                        two_sided: false,
                    })
                } else {
                    LightDesc::Spot {
                        position,
                        direction: axis,
                        inner_deg: 20.0,
                        outer_deg: 30.0,
                        color: [40.0, 35.0, 30.0],
                    }
                },
                ShadowMapDesc {
                    origin: position,
                    basis: light_basis(axis),
                    projection: ShadowProjectionDesc::Perspective {
                        tan_half: 31f64.to_radians().tan(),
                    },
                    near: 0.05,
                    far: 60.0,
                    size: sm_size,
                    bias_texels: 1.5,
                },
            )
        }
    };
    Case {
        family,
        res: Resolutions { screen, rectified },
        camera,
        light,
        medium: MediumDesc {
            sigma_t: 0.08,
            albedo: 0.8,
            g: 0.4,
        },
        shadow,
        settings: FrameSettings::for_screen(screen[0], screen[1]),
        mutations: Some(mutations),
    }
}

impl Case {
    fn apply(&mut self) {
        let cam0 = self.camera;
        for m in self.mutations.clone().unwrap_or_default() {
            match m {
                Mutation::CamPosition(v) => self.camera.position = v.get(&cam0),
                Mutation::CamForward(v) => self.camera.forward = v.get(&cam0),
                Mutation::CamRight(v) => self.camera.right = v.get(&cam0),
                Mutation::CamUp(v) => self.camera.up = v.get(&cam0),
                Mutation::TanHalfFov(x) => self.camera.tan_half_fov_y = x,
                Mutation::Near(x) => self.camera.near = x,
                Mutation::Far(x) => self.camera.far = x,
                Mutation::NearFromFar(f) => self.camera.near = self.camera.far * f,
                Mutation::LightDirection(v) => match &mut self.light {
                    LightDesc::Directional { direction, .. }
                    | LightDesc::Spot { direction, .. }
                    | LightDesc::Area(AreaLightDesc { direction, .. }) => {
                        *direction = v.get(&cam0);
                    }
                },
                Mutation::LightPosition(v) => match &mut self.light {
                    LightDesc::Spot { position, .. }
                    | LightDesc::Area(AreaLightDesc { position, .. }) => {
                        *position = v.get(&cam0);
                    }
                    LightDesc::Directional { .. } => {}
                },
                Mutation::InnerDeg(x) => match &mut self.light {
                    LightDesc::Spot { inner_deg, .. }
                    | LightDesc::Area(AreaLightDesc { inner_deg, .. }) => *inner_deg = x,
                    LightDesc::Directional { .. } => {}
                },
                Mutation::OuterDeg(x) => match &mut self.light {
                    LightDesc::Spot { outer_deg, .. }
                    | LightDesc::Area(AreaLightDesc { outer_deg, .. }) => *outer_deg = x,
                    LightDesc::Directional { .. } => {}
                },
                Mutation::LightColor(i, x) => match &mut self.light {
                    LightDesc::Directional { color, .. }
                    | LightDesc::Spot { color, .. }
                    | LightDesc::Area(AreaLightDesc {
                        radiance: color, ..
                    }) => {
                        color[i] = x;
                    }
                },
                Mutation::SigmaT(x) => self.medium.sigma_t = x,
                Mutation::Albedo(x) => self.medium.albedo = x,
                Mutation::G(x) => self.medium.g = x,
                Mutation::SmOrigin(v) => self.shadow.origin = v.get(&cam0),
                Mutation::SmBasis(i, v) => self.shadow.basis[i] = v.get(&cam0),
                Mutation::SmProjection([x0, x1, y0, y1]) => {
                    self.shadow.projection = ShadowProjectionDesc::Orthographic { x0, x1, y0, y1 };
                }
                Mutation::SmPerspective(tan_half) => {
                    self.shadow.projection = ShadowProjectionDesc::Perspective { tan_half };
                }
                Mutation::SmNear(x) => self.shadow.near = x,
                Mutation::SmFar(x) => self.shadow.far = x,
                Mutation::SmBias(x) => self.shadow.bias_texels = x,
                Mutation::SmSize(n) => self.shadow.size = n,
                Mutation::ScreenWidth(n) => self.res.screen[0] = n,
                Mutation::ScreenHeight(n) => self.res.screen[1] = n,
                Mutation::RectifiedWidth(n) => self.res.rectified[0] = n,
                Mutation::RectifiedHeight(n) => self.res.rectified[1] = n,
                Mutation::EpipoleRadius(x) => self.settings.epipole_radius_px = x,
                Mutation::MarchSteps(n) => self.settings.march_steps = n,
                Mutation::SpotQuadrature(n) => self.settings.spot_quadrature = n,
                Mutation::ProjectiveMaxHalfAngle(x) => {
                    self.settings.projective_max_half_angle_deg = x;
                }
                Mutation::Knobs(regions, bases, bases_per_thread) => {
                    if let FamilyVariant::Prefiltered(v) = &mut self.family {
                        v.regions = regions;
                        v.bases = bases;
                        v.bases_per_thread = bases_per_thread;
                    }
                }
                Mutation::SwapLight => {
                    self.light = match self.light {
                        LightDesc::Directional { direction, color } => LightDesc::Spot {
                            position: cam0.position + DVec3::new(3.0, 5.0, -2.0),
                            direction,
                            inner_deg: 10.0,
                            outer_deg: 20.0,
                            color,
                        },
                        LightDesc::Spot {
                            direction, color, ..
                        } => LightDesc::Directional { direction, color },
                        LightDesc::Area(a) => a.point_limit(),
                    };
                }
            }
        }
    }
}

fn family() -> impl Strategy<Value = FamilyVariant> {
    let grid = PrefilteredVariant::grid(1..=8);
    prop_oneof![
        prop::sample::select(grid).prop_map(FamilyVariant::Prefiltered),
        prop::sample::select(RaymarchVariant::grid()).prop_map(FamilyVariant::Raymarch),
        prop::sample::select(MinmaxVariant::grid()).prop_map(FamilyVariant::Minmax),
        prop::sample::select(HybridVolumeVariant::grid()).prop_map(FamilyVariant::HybridVolume),
        prop::sample::select(PartialSumTreeVariant::grid()).prop_map(FamilyVariant::PartialSumTree),
        prop::sample::select(AreaIvsvVariant::grid()).prop_map(FamilyVariant::AreaIvsv),
    ]
}

fn light_aim() -> impl Strategy<Value = LightAim> {
    let angles = (-std::f64::consts::PI..std::f64::consts::PI, -1.5..1.5f64);
    prop_oneof![
        4 => angles.clone().prop_map(|(a, e)| LightAim::Random(a, e)),
        1 => Just(LightAim::TowardsEye),
        1 => Just(LightAim::AwayFromEye),
        1 => Just(LightAim::AlongUp),
        // Grazing: close to the camera's horizontal plane.
        1 => (angles.0, -0.02..0.02f64).prop_map(|(a, e)| LightAim::Random2(a, e)),
    ]
}

/// A valid base frame of `family` (any family when `None`) with up to three mutations.
fn case(family_of: impl Strategy<Value = FamilyVariant>) -> impl Strategy<Value = Case> {
    (
        family_of,
        (1..=48u32, 1..=48u32),
        (64..=96u32, 1..=48u32),
        1..=64u32,
        (-std::f64::consts::PI..std::f64::consts::PI, -1.2..1.2f64),
        light_aim(),
        prop_oneof![3 => 20.0..120.0f64, 1 => prop::sample::select(vec![0.01, 170.0, 179.9])],
        prop::collection::vec(mutation(), 0..=3),
    )
        .prop_map(|(family, (w, h), (wr, hr), sm, cam, aim, fov, mutations)| {
            // A valid base frame: a rectified width the variant's filtered stride divides
            // (the grid's coarse-column variants have stride x regions^2 <= 64).
            let stride = match family {
                FamilyVariant::Prefiltered(v) => v.filtered_stride.max(1),
                _ => 1,
            };
            let wr = wr - wr % stride;
            let mut c = base_case(family, [w, h], [wr, hr], sm, cam, aim, fov, mutations);
            c.apply();
            c
        })
}

/// A rejection's message: non-empty, one line, naming a mutated field.
fn check_error(case: &Case, message: &str) -> Result<(), TestCaseError> {
    prop_assert!(!message.trim().is_empty(), "empty error message");
    prop_assert!(
        !message.chars().any(char::is_control),
        "error message is not one printable line: {message:?}"
    );
    let Some(mutations) = &case.mutations else {
        return Ok(());
    };
    prop_assert!(
        !mutations.is_empty(),
        "a valid frame was rejected: {message}"
    );
    let named = mutations
        .iter()
        .flat_map(Mutation::keywords)
        .any(|k| message.contains(k));
    prop_assert!(
        named,
        "the error {message:?} names none of the mutated fields {mutations:?}"
    );
    Ok(())
}

fn finite4(what: &str, v: [f32; 4]) -> Result<(), TestCaseError> {
    prop_assert!(
        v.iter().all(|x| x.is_finite()),
        "accepted frame has a non-finite uniform {what} = {v:?}"
    );
    Ok(())
}

fn check_frame_uniforms(u: &FrameUniforms) -> Result<(), TestCaseError> {
    for (what, v) in [
        ("eye", u.eye),
        ("axis", u.axis),
        ("e1", u.e1),
        ("e2", u.e2),
        ("cam_forward", u.cam_forward),
        ("cam_right", u.cam_right),
        ("cam_up", u.cam_up),
        ("theta", u.theta),
        ("medium", u.medium),
        ("light_color", u.light_color),
        ("light_pos", u.light_pos),
        ("light_dir", u.light_dir),
        ("sm_right", u.sm_right),
        ("sm_up", u.sm_up),
        ("sm_forward", u.sm_forward),
        ("sm_origin", u.sm_origin),
        ("sm_proj", u.sm_proj),
        ("epipole", u.epipole),
        ("anti_epipole", u.anti_epipole),
        ("proj", u.proj),
        ("proj_g0", u.proj_g0),
        ("proj_g1", u.proj_g1),
        ("proj_g2", u.proj_g2),
    ] {
        finite4(what, v)?;
    }
    Ok(())
}

fn check_prefiltered_frame(case: &Case, frame: &PrefilteredFrame) -> Result<(), TestCaseError> {
    check_frame_uniforms(&frame.uniforms)?;
    prop_assert_eq!(frame.slices.len(), case.res.rectified[1] as usize);
    let epipolar = frame.report.projective.is_none();
    for (j, s) in frame.slices.iter().enumerate() {
        finite4(
            &format!("slice {j}"),
            [s.delta, s.theta_ref, s.theta_lo, s.theta_hi],
        )?;
        if epipolar {
            prop_assert!(s.delta > 0.0, "slice {j}: column spacing {}", s.delta);
            prop_assert!(s.theta_lo <= s.theta_hi, "slice {j}: {s:?}");
        }
    }
    let t = frame.uniforms.theta;
    prop_assert!(t[0] <= t[1], "theta_lo > theta_hi: {t:?}");
    prop_assert!(
        frame.report.max_slice_gap_px.is_finite(),
        "max_slice_gap_px {}",
        frame.report.max_slice_gap_px
    );
    if let Some(p) = &frame.report.projective {
        for m in &p.matrices {
            prop_assert!(m.is_finite(), "projective matrix {m:?}");
        }
    }
    Ok(())
}

fn check_partial_sum_tree_frame(
    case: &Case,
    frame: &PartialSumTreeFrame,
) -> Result<(), TestCaseError> {
    check_prefiltered_frame(case, &frame.frame)?;
    prop_assert_eq!(frame.factors.len(), FACTOR_VECS as usize);
    for (j, v) in frame.factors.iter().enumerate() {
        finite4(&format!("pst_factors[{j}]"), *v)?;
    }
    let sep = &frame.separable;
    prop_assert!(
        sep.theta_lo <= sep.theta_hi && sep.v_max > 0.0,
        "separable grid {} {} {}",
        sep.v_max,
        sep.theta_lo,
        sep.theta_hi
    );
    Ok(())
}

fn check_raymarch_uniforms(u: &RaymarchUniforms) -> Result<(), TestCaseError> {
    for (what, v) in [
        ("eye", u.eye),
        ("cam_forward", u.cam_forward),
        ("cam_right", u.cam_right),
        ("cam_up", u.cam_up),
        ("medium", u.medium),
        ("light_color", u.light_color),
        ("light_pos", u.light_pos),
        ("light_dir", u.light_dir),
        ("sm_right", u.sm_right),
        ("sm_up", u.sm_up),
        ("sm_forward", u.sm_forward),
        ("sm_origin", u.sm_origin),
        ("sm_proj", u.sm_proj),
    ] {
        finite4(what, v)?;
    }
    Ok(())
}

fn check_area_frame(frame: &AreaIvsvFrame) -> Result<(), TestCaseError> {
    for (i, r) in frame.vpls.iter().enumerate() {
        for (what, v) in [
            ("position", r.position),
            ("color", r.color),
            ("axis", r.axis),
            ("perp_x", r.perp_x),
            ("perp_y", r.perp_y),
            ("spot_dir", r.spot_dir),
            ("sm_origin", r.sm_origin),
            ("sm_proj", r.sm_proj),
        ] {
            finite4(&format!("vpl[{i}].{what}"), v)?;
        }
        prop_assert!(
            r.perp_x[3] > 0.0,
            "vpl[{i}] alpha bin width {}",
            r.perp_x[3]
        );
    }
    for (what, v) in [
        ("eye", frame.uniforms.eye),
        ("medium", frame.uniforms.medium),
    ] {
        finite4(what, v)?;
    }
    Ok(())
}

fn check_case(case: Case) -> Result<(), TestCaseError> {
    let result = match case.family {
        FamilyVariant::AreaIvsv(v) => prepare_area_light(
            &v,
            case.res.screen,
            &case.camera,
            &case.light,
            &case.medium,
            &case.shadow,
        )
        .map(|(f, _)| check_area_frame(&f)),
        FamilyVariant::Prefiltered(v) => prepare_frame(
            &v,
            &case.res,
            &case.camera,
            &case.light,
            &case.medium,
            &case.shadow,
            &case.settings,
        )
        .map(|f| check_prefiltered_frame(&case, &f)),
        FamilyVariant::Minmax(v) => prepare_minmax(
            &v,
            &case.res,
            &case.camera,
            &case.light,
            &case.medium,
            &case.shadow,
            &case.settings,
        )
        .map(|f| check_prefiltered_frame(&case, &f)),
        FamilyVariant::HybridVolume(v) => prepare_hybrid_volume(
            &v,
            &case.res,
            &case.camera,
            &case.light,
            &case.medium,
            &case.shadow,
            &case.settings,
        )
        .map(|f| check_prefiltered_frame(&case, &f)),
        FamilyVariant::PartialSumTree(v) => prepare_partial_sum_tree(
            &v,
            &case.res,
            &case.camera,
            &case.light,
            &case.medium,
            &case.shadow,
            &case.settings,
        )
        .map(|f| check_partial_sum_tree_frame(&case, &f)),
        FamilyVariant::Raymarch(v) => prepare_raymarch(
            &v,
            case.res.screen,
            &case.camera,
            &case.light,
            &case.medium,
            &case.shadow,
        )
        .map(|u| check_raymarch_uniforms(&u)),
    };
    tally(result.is_ok());
    if let (FamilyVariant::Prefiltered(v), Ok(_)) = (&case.family, &result) {
        prop_assert!(
            v.validate().is_ok(),
            "a frame was set up for an invalid variant {v:?}"
        );
    }
    match result {
        Ok(checked) => checked,
        Err(e) => check_error(&case, &e.to_string()),
    }
}

#[test]
fn prepare_frame_on_mutated_frames() {
    let grid = PrefilteredVariant::grid(1..=8);
    run(
        "prepare_frame",
        PREFILTERED_CASES,
        0x5ca7_0001,
        case(prop::sample::select(grid).prop_map(FamilyVariant::Prefiltered)),
        check_case,
    );
}

#[test]
fn prepare_raymarch_on_mutated_frames() {
    run(
        "prepare_raymarch",
        RAYMARCH_CASES,
        0x5ca7_0002,
        case(prop::sample::select(RaymarchVariant::grid()).prop_map(FamilyVariant::Raymarch)),
        check_case,
    );
}

#[test]
fn prepare_minmax_on_mutated_frames() {
    run(
        "prepare_minmax",
        MINMAX_CASES,
        0x5ca7_0003,
        case(prop::sample::select(MinmaxVariant::grid()).prop_map(FamilyVariant::Minmax)),
        check_case,
    );
}

#[test]
fn prepare_hybrid_volume_on_mutated_frames() {
    run(
        "prepare_hybrid_volume",
        HYBRID_VOLUME_CASES,
        0x5ca7_0007,
        case(
            prop::sample::select(HybridVolumeVariant::grid()).prop_map(FamilyVariant::HybridVolume),
        ),
        check_case,
    );
}

#[test]
fn prepare_partial_sum_tree_on_mutated_frames() {
    run(
        "prepare_partial_sum_tree",
        PST_CASES,
        0x5ca7_0006,
        case(
            prop::sample::select(PartialSumTreeVariant::grid())
                .prop_map(FamilyVariant::PartialSumTree),
        ),
        check_case,
    );
}

/// Every input arbitrary: almost always rejected, never a panic, never a NaN.
#[test]
fn every_family_on_arbitrary_numbers() {
    let v3 = || (wild_f64(), wild_f64(), wild_f64()).prop_map(|(x, y, z)| DVec3::new(x, y, z));
    let numbers = (
        family(),
        (wild_u32(), wild_u32(), 1..=64u32, 1..=64u32),
        (v3(), v3(), v3(), v3(), wild_f64(), wild_f64(), wild_f64()),
        (v3(), v3(), wild_f64(), wild_f64(), wild_f64()),
        (wild_f64(), wild_f64(), wild_f64()),
        (v3(), v3(), v3(), v3(), wild_f64(), wild_f64(), wild_f64()),
    );
    run(
        "arbitrary_numbers",
        ARBITRARY_CASES,
        0x5ca7_0004,
        numbers,
        |(family, (w, h, wr, hr), cam, light, medium, sm)| {
            let camera = CameraDesc {
                position: cam.0,
                forward: cam.1,
                right: cam.2,
                up: cam.3,
                tan_half_fov_y: cam.4,
                near: cam.5,
                far: cam.6,
            };
            let light = match family.light() {
                LightKind::Directional => LightDesc::Directional {
                    direction: light.1,
                    color: [light.2, light.3, light.4],
                },
                LightKind::Area => LightDesc::Area(AreaLightDesc {
                    position: light.0,
                    direction: light.1,
                    up: None,
                    shape: AreaShapeDesc::Disk { radius: light.4 },
                    inner_deg: light.2,
                    outer_deg: light.3,
                    radiance: [light.4; 3],
                    two_sided: false,
                }),
                LightKind::Spot => LightDesc::Spot {
                    position: light.0,
                    direction: light.1,
                    inner_deg: light.2,
                    outer_deg: light.3,
                    color: [light.4; 3],
                },
            };
            let medium = MediumDesc {
                sigma_t: medium.0,
                albedo: medium.1,
                g: medium.2,
            };
            let shadow = ShadowMapDesc {
                origin: sm.0,
                basis: [sm.1, sm.2, sm.3],
                projection: ShadowProjectionDesc::Perspective { tan_half: sm.4 },
                near: sm.5,
                far: sm.6,
                size: 16,
                bias_texels: 1.5,
            };
            let case = Case {
                family,
                // Keep the work per case small: huge sizes are the mutations' job.
                res: Resolutions {
                    screen: [w % 65, h % 65],
                    rectified: [wr + 64, hr],
                },
                camera,
                light,
                medium,
                shadow,
                settings: FrameSettings::default(),
                // Everything is arbitrary: the message may name any field.
                mutations: None,
            };
            check_case(case)
        },
    );
}

/// The tree layout of the minmax family never overflows or loops, for any width.
#[test]
fn tree_layout_on_arbitrary_widths() {
    run(
        "tree_layout",
        TREE_CASES,
        0x5ca7_0005,
        prop_oneof![any::<u32>(), 0..70_000u32, Just(u32::MAX), Just(0u32)],
        |w| {
            tally(true);
            let levels = tree_levels(w);
            prop_assert!(levels <= 33, "{levels} levels for width {w}");
            if w > 0 {
                prop_assert_eq!(level_count(levels - 1, w), 1);
            }
            let tw = tree_width(w);
            prop_assert!(u64::from(tw) >= u64::from(w).min(u64::from(u32::MAX)));
            Ok(())
        },
    );
}
