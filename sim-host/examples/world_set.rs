//! Lists the generated world set (`gen-00` .. `gen-23`, see `papillon_sim::world::generated`)
//! as a Markdown table, and with `--png DIR` draws each plan (start marked) to `DIR/gen-NN.png`.
//!
//! `cargo run -p papillon-sim --example world_set -- [--png DIR]`

use std::path::PathBuf;

use papillon::grid::CellClass;
use papillon_sim::render::{Track, render_classes, save_png};
use papillon_sim::world::generated::{self, OpeningKind, Plan};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let png_dir = match args.as_slice() {
        [] => None,
        [flag, dir] if flag == "--png" => Some(PathBuf::from(dir)),
        _ => return Err("usage: world_set [--png DIR]".into()),
    };
    println!(
        "| name | kind | seed | size (m) | cells | narrowest opening (m) | doors | gaps | free area (m²) | footprint reaches (m²) | attempts |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for (i, name) in generated::set_names().iter().enumerate() {
        let plan = Plan::from_set(i).ok_or("set index")?;
        let (w, h) = plan.size_m();
        let (cw, ch) = plan.size_cells();
        let doors = plan
            .openings()
            .iter()
            .filter(|o| o.kind == OpeningKind::Door)
            .count();
        let gaps = plan.openings().len() - doors;
        let reach = plan.reach();
        println!(
            "| {name} | {} | {} | {w:.1} x {h:.1} | {} | {:.1} | {doors} | {gaps} | {:.0} | {:.0} | {} |",
            plan.kind().name(),
            plan.seed(),
            cw * ch,
            plan.narrowest_opening_m(),
            plan.free_area_m2(),
            reach.reached_cells() as f32 * 0.01,
            plan.attempts(),
        );
        if let Some(dir) = &png_dir {
            std::fs::create_dir_all(dir)?;
            let world = plan.world(0.1)?;
            let track = Track {
                trajectory: vec![world.start().position()],
                targets: vec![world.start().position()],
            };
            let img = render_classes(
                world.geometry(),
                |c| {
                    if world.is_blocked_index(c) {
                        CellClass::Occupied
                    } else {
                        CellClass::Free
                    }
                },
                &[track],
                2,
            );
            save_png(&img, &dir.join(format!("{name}.png")))?;
        }
    }
    Ok(())
}
