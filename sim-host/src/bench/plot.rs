//! The sweep's plots, one set per map, each as PNG and SVG (plotters; text drawn with the
//! embedded DejaVu Sans Mono font, so no system font is needed):
//!
//! - `coverage-MAP`: coverage vs steps per series, the mean with a band from the smallest to
//!   the largest run;
//! - `pareto-MAP`: mean decision time vs mean final coverage per series, the Pareto front
//!   (less time, more coverage) filled and joined;
//! - `convergence-MAP`: best fitness vs generation of the runs' first decision, mean over the
//!   runs, per optimizer series (the frontier selectors have no generations);
//! - `cost-MAP`: the thesis's cost figures, fitness evaluations per run and mean computation
//!   time per decision, one bar per series.
//!
//! A series is a group of runs ([`GroupKey`]), named by the method plus whatever else varies
//! on that map (strategy, population, robots).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::record::RunRecord;
use super::summary::GroupKey;

/// The embedded font, its family name and its registration: the map pictures' own
/// ([`papillon::picture`]).
pub(crate) use papillon::picture::{FAMILY, register_font};
/// Picture size \[px\].
const SIZE: (u32, u32) = (960, 640);
/// Points of the common steps grid the coverage curves are resampled on.
const GRID_POINTS: usize = 200;

/// One series: its name and its runs' results.
struct Series<'a> {
    name: String,
    runs: Vec<&'a super::record::RunResult>,
}

/// The series of each map, in key order.
fn series_by_map(records: &[RunRecord]) -> BTreeMap<String, Vec<Series<'_>>> {
    let mut groups: BTreeMap<GroupKey, Vec<&RunRecord>> = BTreeMap::new();
    for r in records {
        groups.entry(GroupKey::of(r)).or_default().push(r);
    }
    let mut by_map: BTreeMap<String, Vec<(GroupKey, Vec<&RunRecord>)>> = BTreeMap::new();
    for (k, rs) in groups {
        by_map.entry(k.map.clone()).or_default().push((k, rs));
    }
    by_map
        .into_iter()
        .map(|(map, groups)| {
            let varies = |f: &dyn Fn(&GroupKey) -> String| {
                let first = f(&groups[0].0);
                groups.iter().any(|(k, _)| f(k) != first)
            };
            let strat = varies(&|k| format!("{}{}", k.strategy, k.targets));
            let pop = varies(&|k| k.population.to_string());
            let robots = varies(&|k| k.robots.to_string());
            let objective = varies(&|k| k.objective.clone());
            let preset = varies(&|k| k.preset.clone());
            let series = groups
                .into_iter()
                .map(|(k, rs)| {
                    let mut name = k.method.clone();
                    if strat {
                        name += &format!(" {}-k{}", k.strategy, k.targets);
                    }
                    if pop {
                        name += &format!(" pop{}", k.population);
                    }
                    if robots {
                        name += &format!(" {}r", k.robots);
                    }
                    if objective {
                        name += &format!(" ({})", k.objective);
                    }
                    if preset {
                        name += &format!(" ({} preset)", k.preset);
                    }
                    Series {
                        name,
                        runs: rs.iter().filter_map(|r| r.result.as_ref().ok()).collect(),
                    }
                })
                .filter(|s| !s.runs.is_empty())
                .collect();
            (map, series)
        })
        .collect()
}

/// Coverage of a curve at `steps`: the last sample at or before it (held after the end).
fn coverage_at(curve: &[(f32, f32)], steps: f32) -> f32 {
    let i = curve.partition_point(|&(s, _)| s <= steps);
    if i == 0 { 0.0 } else { curve[i - 1].1 }
}

/// Mean, min and max coverage of `runs` on `grid`.
fn band(runs: &[&super::record::RunResult], grid: &[f32]) -> Vec<(f32, f32, f32, f32)> {
    grid.iter()
        .map(|&s| {
            let v: Vec<f32> = runs
                .iter()
                .map(|r| coverage_at(&r.coverage_curve, s))
                .collect();
            let mean = v.iter().sum::<f32>() / v.len() as f32;
            let min = v.iter().copied().fold(f32::INFINITY, f32::min);
            let max = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            (s, mean, min, max)
        })
        .collect()
}

/// Indices of the points on the Pareto front of (time, coverage): no other point has less or
/// equal time and more or equal coverage with one of them strictly better.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    (0..points.len())
        .filter(|&i| {
            let (t, c) = points[i];
            !points
                .iter()
                .enumerate()
                .any(|(j, &(tj, cj))| j != i && tj <= t && cj >= c && (tj < t || cj > c))
        })
        .collect()
}

fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("plot: {e:?}")
}

type Area<'a, DB> = DrawingArea<DB, Shift>;

fn draw_coverage<DB: DrawingBackend>(
    root: &Area<'_, DB>,
    map: &str,
    series: &[Series<'_>],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let max_steps = series
        .iter()
        .flat_map(|s| s.runs.iter())
        .filter_map(|r| r.coverage_curve.last().map(|&(s, _)| s))
        .fold(1.0f32, f32::max);
    let grid: Vec<f32> = (0..=GRID_POINTS)
        .map(|i| max_steps * i as f32 / GRID_POINTS as f32)
        .collect();
    let mut chart = ChartBuilder::on(root)
        .caption(format!("Coverage vs steps, {map}"), (FAMILY, 24))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d(0f32..max_steps * 1.02, 0f32..100f32)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("steps (summed over robots)")
        .y_desc("coverage [%]")
        .label_style((FAMILY, 14))
        .draw()
        .map_err(err)?;
    for (i, s) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let b = band(&s.runs, &grid);
        let mut poly: Vec<(f32, f32)> = b.iter().map(|&(x, _, _, hi)| (x, 100.0 * hi)).collect();
        poly.extend(b.iter().rev().map(|&(x, _, lo, _)| (x, 100.0 * lo)));
        chart
            .draw_series(std::iter::once(Polygon::new(
                poly,
                color.mix(0.15).filled(),
            )))
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                b.iter().map(|&(x, m, _, _)| (x, 100.0 * m)),
                color.stroke_width(2),
            ))
            .map_err(err)?
            .label(format!("{} (n={})", s.name, s.runs.len()))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FAMILY, 13))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

fn draw_pareto<DB: DrawingBackend>(
    root: &Area<'_, DB>,
    map: &str,
    series: &[Series<'_>],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    // One point per series: mean decision time [ms] (at least 1 µs for the log axis) and mean
    // final coverage [%].
    let points: Vec<(f64, f64)> = series
        .iter()
        .map(|s| {
            let times: Vec<f64> = s
                .runs
                .iter()
                .flat_map(|r| r.decision_ms.iter().copied())
                .collect();
            let t = if times.is_empty() {
                1e-3
            } else {
                (times.iter().sum::<f64>() / times.len() as f64).max(1e-3)
            };
            let c = s.runs.iter().map(|r| r.coverage as f64).sum::<f64>() / s.runs.len() as f64;
            (t, 100.0 * c)
        })
        .collect();
    let front = pareto_front(&points);
    let tmin = points.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let tmax = points.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let cmin = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let cmax = points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let pad = ((cmax - cmin) * 0.1).max(0.5);
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("Decision time vs final coverage, {map} (Pareto front filled)"),
            (FAMILY, 22),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d(
            ((tmin / 2.0)..(tmax * 2.0)).log_scale(),
            (cmin - pad)..(cmax + pad).min(100.0 + pad),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("mean decision time [ms] (log)")
        .y_desc("mean final coverage [%]")
        .label_style((FAMILY, 14))
        .draw()
        .map_err(err)?;
    let mut on_front: Vec<(f64, f64)> = front.iter().map(|&i| points[i]).collect();
    on_front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(on_front, BLACK.stroke_width(1)))
        .map_err(err)?;
    for (i, (s, &p)) in series.iter().zip(&points).enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let filled = front.contains(&i);
        let style = if filled {
            color.filled()
        } else {
            color.stroke_width(2)
        };
        let font = (FAMILY, 12).into_font().color(&BLACK);
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(p)
                    + Circle::new((0, 0), 6, style)
                    + Text::new(s.name.clone(), (9, -6), font),
            ))
            .map_err(err)?;
    }
    root.present().map_err(err)
}

fn draw_convergence<DB: DrawingBackend>(
    root: &Area<'_, DB>,
    map: &str,
    series: &[Series<'_>],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    // Mean over the runs of each generation's best fitness (runs shorter than the longest
    // hold their last value).
    let curves: Vec<(usize, &Series<'_>, Vec<f32>)> = series
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let hs: Vec<&Vec<f32>> = s
                .runs
                .iter()
                .map(|r| &r.convergence)
                .filter(|h| !h.is_empty())
                .collect();
            let len = hs.iter().map(|h| h.len()).max()?;
            let mean = (0..len)
                .map(|g| hs.iter().map(|h| h[g.min(h.len() - 1)]).sum::<f32>() / hs.len() as f32)
                .collect();
            Some((i, s, mean))
        })
        .collect();
    let gmax = curves.iter().map(|c| c.2.len()).max().unwrap_or(2).max(2) - 1;
    let fmin = curves
        .iter()
        .flat_map(|c| c.2.iter().copied())
        .fold(f32::INFINITY, f32::min);
    let fmax = curves
        .iter()
        .flat_map(|c| c.2.iter().copied())
        .fold(f32::NEG_INFINITY, f32::max);
    let (fmin, fmax) = if fmin.is_finite() && fmax > fmin {
        let pad = (fmax - fmin) * 0.05;
        (fmin - pad, fmax + pad)
    } else if fmin.is_finite() {
        (fmin - 1.0, fmin + 1.0)
    } else {
        (0.0, 1.0)
    };
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("Convergence of the first decision, {map} (mean over runs)"),
            (FAMILY, 22),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(72)
        .build_cartesian_2d(0f32..gmax as f32, fmin..fmax)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("generation")
        .y_desc("best fitness (lower is better)")
        .label_style((FAMILY, 14))
        .draw()
        .map_err(err)?;
    for (i, s, mean) in &curves {
        let color = Palette99::pick(*i).to_rgba();
        chart
            .draw_series(LineSeries::new(
                mean.iter().enumerate().map(|(g, &f)| (g as f32, f)),
                color.stroke_width(2),
            ))
            .map_err(err)?
            .label(s.name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
    }
    if !curves.is_empty() {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FAMILY, 13))
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)
}

/// One panel of horizontal bars: `values[i]` for series `i`.
fn draw_bars<DB: DrawingBackend>(
    area: &Area<'_, DB>,
    title: &str,
    x_desc: &str,
    names: &[String],
    values: &[f64],
) -> Result<(), String> {
    let n = values.len().max(1);
    let vmax = values.iter().copied().fold(0.0f64, f64::max).max(1e-9) * 1.1;
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FAMILY, 18))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(150)
        .build_cartesian_2d(0.0..vmax, -0.5..(n as f64 - 0.5))
        .map_err(err)?;
    let labels = names.to_vec();
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(n)
        .y_label_formatter(&move |y: &f64| {
            let i = y.round();
            if (y - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .x_desc(x_desc)
        .label_style((FAMILY, 12))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(values.iter().enumerate().map(|(i, &v)| {
            let y = i as f64;
            Rectangle::new(
                [(0.0, y - 0.35), (v, y + 0.35)],
                Palette99::pick(i).to_rgba().filled(),
            )
        }))
        .map_err(err)?;
    Ok(())
}

fn draw_cost<DB: DrawingBackend>(
    root: &Area<'_, DB>,
    map: &str,
    series: &[Series<'_>],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let names: Vec<String> = series.iter().map(|s| s.name.clone()).collect();
    let mean = |s: &Series<'_>, f: &dyn Fn(&super::record::RunResult) -> f64| {
        s.runs.iter().map(|r| f(r)).sum::<f64>() / s.runs.len().max(1) as f64
    };
    let evals: Vec<f64> = series
        .iter()
        .map(|s| mean(s, &|r| r.fitness_evals as f64))
        .collect();
    let times: Vec<f64> = series
        .iter()
        .map(|s| {
            let t: Vec<f64> = s
                .runs
                .iter()
                .flat_map(|r| r.decision_ms.iter().copied())
                .collect();
            t.iter().sum::<f64>() / t.len().max(1) as f64
        })
        .collect();
    let panels = root.split_evenly((1, 2));
    draw_bars(
        &panels[0],
        &format!("Fitness evaluations per run, {map}"),
        "evaluations (mean over runs)",
        &names,
        &evals,
    )?;
    draw_bars(
        &panels[1],
        &format!("Computation time per decision, {map}"),
        "mean decision time [ms]",
        &names,
        &times,
    )?;
    root.present().map_err(err)
}

/// Draws one picture as SVG and PNG.
fn render(
    dir: &Path,
    name: &str,
    svg: impl FnOnce(&Area<'_, SVGBackend<'_>>) -> Result<(), String>,
    png: impl FnOnce(&Area<'_, BitMapBackend<'_>>) -> Result<(), String>,
) -> Result<Vec<PathBuf>, String> {
    let svg_path = dir.join(format!("{name}.svg"));
    {
        let root = SVGBackend::new(&svg_path, SIZE).into_drawing_area();
        svg(&root)?;
    }
    let png_path = dir.join(format!("{name}.png"));
    let mut buf = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
        png(&root)?;
    }
    let img = image::RgbImage::from_raw(SIZE.0, SIZE.1, buf)
        .ok_or_else(|| "plot: bad picture buffer".to_string())?;
    img.save(&png_path)
        .map_err(|e| format!("{}: cannot write: {e}", png_path.display()))?;
    Ok(vec![png_path, svg_path])
}

/// File-name-safe form of a label.
fn safe(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Draws every plot of `records` into `dir`; returns the files written.
pub fn write_plots(dir: &Path, records: &[RunRecord]) -> Result<Vec<PathBuf>, String> {
    register_font();
    let mut files = Vec::new();
    for (map, series) in series_by_map(records) {
        if series.is_empty() {
            continue;
        }
        let m = safe(&map);
        files.extend(render(
            dir,
            &format!("coverage-{m}"),
            |a| draw_coverage(a, &map, &series),
            |a| draw_coverage(a, &map, &series),
        )?);
        files.extend(render(
            dir,
            &format!("pareto-{m}"),
            |a| draw_pareto(a, &map, &series),
            |a| draw_pareto(a, &map, &series),
        )?);
        files.extend(render(
            dir,
            &format!("convergence-{m}"),
            |a| draw_convergence(a, &map, &series),
            |a| draw_convergence(a, &map, &series),
        )?);
        files.extend(render(
            dir,
            &format!("cost-{m}"),
            |a| draw_cost(a, &map, &series),
            |a| draw_cost(a, &map, &series),
        )?);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pareto_front_keeps_the_undominated_points() {
        let pts = [
            (1.0, 90.0),
            (2.0, 95.0),
            (3.0, 94.0),
            (0.5, 80.0),
            (2.0, 95.0),
        ];
        // (3, 94) is dominated by (2, 95); the two equal points do not dominate each other.
        assert_eq!(pareto_front(&pts), vec![0, 1, 3, 4]);
    }

    #[test]
    fn coverage_is_held_between_samples_and_after_the_end() {
        let c = [(0.0, 0.1), (2.0, 0.5), (5.0, 0.9)];
        assert_eq!(coverage_at(&c, -1.0), 0.0);
        assert_eq!(coverage_at(&c, 1.0), 0.1);
        assert_eq!(coverage_at(&c, 2.0), 0.5);
        assert_eq!(coverage_at(&c, 100.0), 0.9);
    }

    #[test]
    fn the_embedded_font_parses() {
        assert!(
            plotters::style::register_font("test-font", FontStyle::Normal, papillon::picture::FONT)
                .is_ok()
        );
    }
}
