//! Writes the input directory of the foreign engine (`examples/foreign_engine`) for a suite
//! scene: `frame.json` (camera, light, medium, shadow map, sizes), `depth.pfm`,
//! `shadow_map.pfm` and, with `--rectification projective` when the frame is projective,
//! `rectified.pfm` (the reference's ray-cast stand-in for the rasterised rectified map).
//!
//! ```text
//! cargo run -p scatter-gen -- --out /tmp/shaders --target spirv,wgsl
//! cargo run --release -p scatter-examples --example foreign_inputs -- --scene columns --out /tmp/inputs
//! cargo run --release -p scatter-foreign-engine -- --shaders /tmp/shaders --inputs /tmp/inputs --out /tmp/inscatter.pfm
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use scatter_foreign_engine::files::{FrameFile, write_inputs};
use scatter_foreign_engine::prefiltered::Sizes;
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::kernels::engine_rectified_map;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_shaderlib::prefiltered::{
    FrameSettings, PrefilteredVariant, Rectification, Resolutions, prepare_frame,
};

/// Writes frame.json and the PFM inputs of the foreign engine for a suite scene.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Suite scene: sphere, columns, window, foliage, terrain, spot_grate.
    #[arg(long, default_value = "columns", value_parser = |s: &str| s.parse::<SceneName>())]
    scene: SceneName,
    /// Camera pose: ordinary, epipole_on_screen, light_behind, grazing.
    #[arg(long, default_value = "ordinary", value_parser = |s: &str| s.parse::<Pose>())]
    pose: Pose,
    /// Screen width.
    #[arg(long, default_value_t = 320)]
    width: u32,
    /// Screen height.
    #[arg(long, default_value_t = 180)]
    height: u32,
    /// Rectified map width and height (square).
    #[arg(long, default_value_t = 256)]
    rectified: u32,
    /// Standard shadow map size.
    #[arg(long, default_value_t = 512)]
    shadow_map: u32,
    /// Also write rectified.pfm when a variant with this rectification gets a projective
    /// frame.
    #[arg(long, default_value = "epipolar", value_parser = |s: &str| s.parse::<Rectification>())]
    rectification: Rectification,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

fn run(args: &Args) -> Result<(), String> {
    let scene = suite::scene(
        args.scene,
        args.pose,
        MediumPreset::Default,
        args.width,
        args.height,
    );
    let bvh = Bvh::build(&scene.geometry);
    let gbuf = GBuffer::cast(&scene, &bvh);
    let shadow = ShadowMap::build(&scene, &bvh, args.shadow_map).map_err(|e| e.to_string())?;
    let sizes = Sizes {
        screen: [gbuf.width, gbuf.height],
        rectified: [args.rectified; 2],
        shadow_map: args.shadow_map,
    };
    let settings = FrameSettings::for_screen(gbuf.width, gbuf.height);
    let (camera, light, medium) = (scene.camera_desc(), scene.light_desc(), scene.medium_desc());
    let variant = PrefilteredVariant {
        light: light.kind(),
        rectification: args.rectification,
        ..PrefilteredVariant::default()
    };
    let frame = prepare_frame(
        &variant,
        &Resolutions {
            screen: sizes.screen,
            rectified: sizes.rectified,
        },
        &camera,
        &light,
        &medium,
        &shadow.desc(),
        &settings,
    )
    .map_err(|e| e.to_string())?;
    let rectified = engine_rectified_map(&scene, &bvh, &frame);
    let file = FrameFile::new(sizes, &camera, &light, &medium, &shadow.desc(), &settings);
    write_inputs(
        &args.out,
        &file,
        &gbuf.view_depth,
        &shadow.depth,
        rectified.as_deref(),
    )
    .map_err(|e| e.to_string())?;
    println!(
        "wrote {} ({} {}, {}x{}, {} light, {} frame for {} variants{})",
        args.out.display(),
        args.scene,
        args.pose,
        sizes.screen[0],
        sizes.screen[1],
        variant.light,
        frame.report.rectification,
        args.rectification,
        if rectified.is_some() {
            ", with rectified.pfm"
        } else {
            ""
        }
    );
    Ok(())
}

fn main() -> ExitCode {
    match run(&Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("foreign_inputs: {e}");
            ExitCode::FAILURE
        }
    }
}
