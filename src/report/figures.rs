//! The report's five SVG figures, drawn with plotters' SVG backend (no fonts are loaded: text is left to
//! the browser). Each function returns one `<svg>` element as text. Long runs are thinned to at most
//! [`MAX_POINTS_PER_SERIES`] points per line so a 40 000-frame run stays a small file; the thinning keeps
//! the first and last points and is deterministic.

use super::html::{ReportInput, ReportRun};
use crate::geometry::{BoundaryKind, HULL_HALF_WIDTH_UNITS};
use crate::optimise::bound::SpeedBound;
use crate::physics::curvature::{circumradius, max_accel_radii};
use crate::physics::{MovementVars, Vec2};
use crate::sim::{FrameRecord, Trace};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::error::Error as StdError;
use std::io;

/// Most points drawn per line or scatter.
pub const MAX_POINTS_PER_SERIES: usize = 2000;
/// Hull boxes drawn along each run in the corridor figure (besides the marked frames).
pub const HULL_BOXES_PER_RUN: usize = 6;
/// Speeds at which the section-9 relations are sampled for the radius figure.
const RELATION_SAMPLES: usize = 120;

/// Width of every figure, pixels.
pub const FIGURE_WIDTH_PX: u32 = 960;
const MARGIN_PX: u32 = 12;
const CAPTION_PX: u32 = 34;
const X_LABEL_PX: u32 = 44;
const Y_LABEL_PX: u32 = 72;
/// Height of the empty band above the corridor that holds its legend, pixels.
const LEGEND_BAND_PX: u32 = 120;
/// Longest corridor (length over width) drawn to scale.
pub const CORRIDOR_MAX_ASPECT: f64 = 8.0;

type Draw = Result<(), Box<dyn StdError>>;

/// Line colours of the runs, in order (the lower bound is grey).
pub const RUN_COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];
const BOUND_COLOUR: RGBColor = RGBColor(110, 110, 110);
const RULE_COLOUR: RGBColor = RGBColor(230, 140, 0);
const SOLID_COLOUR: RGBColor = RGBColor(20, 20, 20);
const FINISH_COLOUR: RGBColor = RGBColor(0, 150, 60);
const MARK_COLOUR: RGBColor = RGBColor(200, 0, 0);

fn run_colour(i: usize) -> RGBColor {
    RUN_COLOURS[i % RUN_COLOURS.len()]
}

/// Frame 0 (the start) and every frame of `trace`.
pub(crate) fn records(trace: &Trace) -> impl Iterator<Item = &FrameRecord> {
    std::iter::once(&trace.start).chain(trace.frames.iter())
}

/// At most `max` of `v`, evenly strided, always with the first and the last.
pub(crate) fn thin<T: Copy>(v: &[T], max: usize) -> Vec<T> {
    if v.len() <= max || max < 2 {
        return v.to_vec();
    }
    let stride = v.len().div_ceil(max - 1);
    let mut out: Vec<T> = v.iter().step_by(stride).copied().collect();
    if (v.len() - 1) % stride != 0 {
        if let Some(&last) = v.last() {
            out.push(last);
        }
    }
    out
}

fn svg_figure(
    height_px: u32,
    draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> Draw,
) -> io::Result<String> {
    let mut out = String::new();
    let result = (|| -> Draw {
        let root =
            SVGBackend::with_string(&mut out, (FIGURE_WIDTH_PX, height_px)).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
        Ok(())
    })();
    result.map_err(|e| io::Error::other(format!("drawing a figure: {e}")))?;
    Ok(out)
}

/// A bounding box of points, grown as points are added (non-finite points are skipped).
#[derive(Clone, Copy, Debug)]
struct Extent {
    lo: Vec2,
    hi: Vec2,
}

impl Extent {
    fn new() -> Self {
        Extent {
            lo: Vec2::new(f64::INFINITY, f64::INFINITY),
            hi: Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        }
    }

    fn add(&mut self, p: Vec2) {
        if p.is_finite() {
            self.lo = Vec2::new(self.lo.x.min(p.x), self.lo.y.min(p.y));
            self.hi = Vec2::new(self.hi.x.max(p.x), self.hi.y.max(p.y));
        }
    }

    /// `(x0, x1, y0, y1)` grown by `pad` on each side (a 200-unit box round the origin when empty).
    fn padded(&self, pad: f64) -> (f64, f64, f64, f64) {
        if !(self.lo.x <= self.hi.x && self.lo.y <= self.hi.y) {
            return (-100.0, 100.0, -100.0, 100.0);
        }
        (
            self.lo.x - pad,
            self.hi.x + pad,
            self.lo.y - pad,
            self.hi.y + pad,
        )
    }
}

/// A range `[lo, hi]` of `values` (finite ones) with a margin, never empty.
fn value_range(values: impl Iterator<Item = f64>, margin_frac: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return (0.0, 1.0);
    }
    let span = (hi - lo).max(1e-9 * hi.abs().max(1.0)).max(1e-6);
    (lo - margin_frac * span, hi + margin_frac * span)
}

/// The last time any run or the bound reaches, seconds.
fn end_time(input: &ReportInput) -> f64 {
    input
        .runs
        .iter()
        .filter_map(|r| r.trace.frames.last().map(|f| f.time))
        .fold(input.bound.crossing.time, f64::max)
        .max(input.scene.frame_time_s())
}

/// A chart over `f64 x f64` data coordinates on the SVG backend.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The corridor figure's layout: the data range shown, pixels per unit along each axis, the figure's
/// height and its title.
#[derive(Clone, Debug)]
struct CorridorLayout {
    x: (f64, f64),
    y: (f64, f64),
    px_per_x: f64,
    px_per_y: f64,
    height_px: u32,
    title: String,
}

/// Everything the corridor figure shows: walls, the finish line, the bound's shortest path, each run.
fn corridor_extent(input: &ReportInput) -> Extent {
    let scene = input.scene;
    let mut ext = Extent::new();
    for w in &scene.walls {
        w.points.iter().for_each(|p| ext.add(*p));
    }
    ext.add(scene.finish.a);
    ext.add(scene.finish.b);
    input.bound.path.iter().for_each(|p| ext.add(*p));
    for run in &input.runs {
        records(run.trace).for_each(|r| ext.add(r.pos));
    }
    ext
}

/// One unit is the same length across and up: fit the plot area to the data's aspect, then widen the
/// shorter range to fill it. A corridor more than [`CORRIDOR_MAX_ASPECT`] times longer than wide (a 100 m
/// lane) would be a hairline to scale, so its cross direction is stretched and the title says so. An empty
/// band on top holds the legend, so it never hides a path.
fn corridor_layout(input: &ReportInput) -> CorridorLayout {
    let (x0, x1, y0, y1) = corridor_extent(input).padded(2.5 * HULL_HALF_WIDTH_UNITS);
    let plot_w = f64::from(FIGURE_WIDTH_PX - 2 * MARGIN_PX - Y_LABEL_PX);
    let (dx, dy) = (x1 - x0, y1 - y0);
    let to_scale = dx / dy <= CORRIDOR_MAX_ASPECT && dy / dx <= CORRIDOR_MAX_ASPECT;
    let plot_h = if to_scale {
        (plot_w * dy / dx).clamp(260.0, 900.0)
    } else {
        360.0
    };
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let (mut px_per_x, mut px_per_y) = (plot_w / dx, plot_h / dy);
    if to_scale {
        let per_unit = px_per_x.min(px_per_y);
        (px_per_x, px_per_y) = (per_unit, per_unit);
    }
    let x = (cx - 0.5 * plot_w / px_per_x, cx + 0.5 * plot_w / px_per_x);
    let y = (
        cy - 0.5 * plot_h / px_per_y,
        cy + 0.5 * plot_h / px_per_y + f64::from(LEGEND_BAND_PX) / px_per_y,
    );
    let height_px =
        plot_h.round() as u32 + LEGEND_BAND_PX + 2 * MARGIN_PX + CAPTION_PX + X_LABEL_PX;
    let title = if to_scale {
        format!(
            "{}: the corridor and the paths (to scale)",
            input.scene.name
        )
    } else {
        format!(
            "{}: the corridor and the paths (y stretched {:.1}x)",
            input.scene.name,
            px_per_y / px_per_x
        )
    };
    CorridorLayout {
        x,
        y,
        px_per_x,
        px_per_y,
        height_px,
        title,
    }
}

/// A legend entry drawn as a short line in `style`.
fn line_legend(style: ShapeStyle) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style)
}

/// Solid walls (black), rule lines (orange, dashed) and the finish line (green), each kind once in the
/// legend.
fn draw_boundaries(chart: &mut Chart, input: &ReportInput) -> Draw {
    let scene = input.scene;
    let (mut rule_labelled, mut solid_labelled) = (false, false);
    for wall in &scene.walls {
        let mut pts: Vec<(f64, f64)> = wall.points.iter().map(|p| (p.x, p.y)).collect();
        if wall.closed {
            if let Some(&first) = pts.first() {
                pts.push(first);
            }
        }
        match wall.kind {
            BoundaryKind::Rule => {
                let style = RULE_COLOUR.stroke_width(2);
                let s = chart.draw_series(DashedLineSeries::new(pts, 10, 6, style))?;
                if !rule_labelled {
                    rule_labelled = true;
                    s.label("rule line (must not be crossed)")
                        .legend(line_legend(style));
                }
            }
            BoundaryKind::Solid => {
                let style = SOLID_COLOUR.stroke_width(3);
                let s = chart.draw_series(LineSeries::new(pts, style))?;
                if !solid_labelled {
                    solid_labelled = true;
                    s.label("solid wall").legend(line_legend(style));
                }
            }
        }
    }
    let finish = FINISH_COLOUR.stroke_width(4);
    chart
        .draw_series(LineSeries::new(
            [
                (scene.finish.a.x, scene.finish.a.y),
                (scene.finish.b.x, scene.finish.b.y),
            ],
            finish,
        ))?
        .label("finish line")
        .legend(line_legend(finish));
    Ok(())
}

/// The lower bound's shortest path of the hull centre (grey, dashed).
fn draw_bound_path(chart: &mut Chart, input: &ReportInput) -> Draw {
    let style = BOUND_COLOUR.stroke_width(1);
    let pts: Vec<(f64, f64)> = input.bound.path.iter().map(|p| (p.x, p.y)).collect();
    chart
        .draw_series(DashedLineSeries::new(pts, 4, 4, style))?
        .label("shortest path (lower bound)")
        .legend(line_legend(style));
    Ok(())
}

/// The 32 x 32 hull centred at `p`.
fn hull_box(p: Vec2, style: ShapeStyle) -> Rectangle<(f64, f64)> {
    let h = HULL_HALF_WIDTH_UNITS;
    Rectangle::new([(p.x - h, p.y - h), (p.x + h, p.y + h)], style)
}

/// [`HULL_BOXES_PER_RUN`] evenly spaced positions of `recs`, the first and the last included.
fn hull_box_positions(recs: &[&FrameRecord]) -> Vec<Vec2> {
    let n = recs.len();
    let count = HULL_BOXES_PER_RUN.min(n);
    (0..count)
        .map(|k| {
            recs[if count > 1 {
                k * (n - 1) / (count - 1)
            } else {
                0
            }]
            .pos
        })
        .collect()
}

/// Run `i`'s path in its colour, with the hull at a few frames (labelled once, for the first run).
fn draw_run_path(chart: &mut Chart, i: usize, run: &ReportRun) -> Draw {
    let colour = run_colour(i);
    let recs: Vec<&FrameRecord> = records(run.trace).filter(|r| r.pos.is_finite()).collect();
    let pts: Vec<(f64, f64)> = recs.iter().map(|r| (r.pos.x, r.pos.y)).collect();
    let line = colour.stroke_width(2);
    chart
        .draw_series(LineSeries::new(thin(&pts, MAX_POINTS_PER_SERIES), line))?
        .label(if run.label == run.trace.controller {
            run.label.to_string()
        } else {
            format!("{} ({})", run.label, run.trace.controller)
        })
        .legend(line_legend(line));
    let box_style = colour.mix(0.7).stroke_width(1);
    let s = chart.draw_series(
        hull_box_positions(&recs)
            .into_iter()
            .map(|p| hull_box(p, box_style)),
    )?;
    if i == 0 {
        s.label("32 x 32 hull at a few frames")
            .legend(move |(x, y)| Rectangle::new([(x + 4, y - 6), (x + 16, y + 6)], box_style));
    }
    Ok(())
}

/// A red hull and cross at the run's first rule violation and first wall contact, each with its label
/// beside the hull on the side with room.
fn draw_run_marks(chart: &mut Chart, run: &ReportRun, layout: &CorridorLayout) -> Draw {
    let h = HULL_HALF_WIDTH_UNITS;
    let marks = [
        (run.trace.first_rule_violation(), "rule broken"),
        (run.trace.first_contact(), "first wall contact"),
    ];
    for (frame, what) in marks {
        let Some(frame) = frame else { continue };
        let Some(rec) = run.trace.frames.iter().find(|f| f.frame == frame) else {
            continue;
        };
        if !rec.pos.is_finite() {
            continue;
        }
        let mark = MARK_COLOUR.stroke_width(2);
        chart.draw_series([hull_box(rec.pos, mark)])?;
        chart.draw_series([Cross::new((rec.pos.x, rec.pos.y), 8, mark)])?;
        let text = format!("{}: {what}, frame {frame}", run.label);
        // About 7 px a character.
        let text_w = 7.0 * text.chars().count() as f64 / layout.px_per_x;
        let gap = 1.5 * h.max(6.0 / layout.px_per_x);
        let tx = if rec.pos.x + gap + text_w > layout.x.1 {
            rec.pos.x - gap - text_w
        } else {
            rec.pos.x + gap
        };
        chart.draw_series([Text::new(
            text,
            (tx, rec.pos.y + 1.5 * h.max(6.0 / layout.px_per_y)),
            ("sans-serif", 14).into_font().color(&MARK_COLOUR),
        )])?;
    }
    Ok(())
}

/// The legend box in `position`, the same style in every figure.
fn draw_legend<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>, position: SeriesLabelPosition) -> Draw {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()?;
    Ok(())
}

/// Axes with a light grid and the given descriptions.
fn draw_axes(chart: &mut Chart, x_desc: &str, y_desc: &str) -> Draw {
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    Ok(())
}

/// Figure 1: the corridor, to scale: solid walls (black), rule lines (orange, dashed), the finish line
/// (green), the lower bound's shortest path (grey, dashed), each run's path with the 32 x 32 hull at a few
/// frames, and a red cross at each run's first rule violation and first wall contact.
pub fn corridor_svg(input: &ReportInput) -> io::Result<String> {
    let layout = corridor_layout(input);
    svg_figure(layout.height_px, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(&layout.title, ("sans-serif", 20))
            .margin(MARGIN_PX)
            .x_label_area_size(X_LABEL_PX)
            .y_label_area_size(Y_LABEL_PX)
            .build_cartesian_2d(layout.x.0..layout.x.1, layout.y.0..layout.y.1)?;
        draw_axes(&mut chart, "x (units)", "y (units)")?;
        draw_boundaries(&mut chart, input)?;
        draw_bound_path(&mut chart, input)?;
        for (i, run) in input.runs.iter().enumerate() {
            draw_run_path(&mut chart, i, run)?;
            draw_run_marks(&mut chart, run, &layout)?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
    })
}

/// The lower bound's speed profile: the speed after each frame from the start speed, iterating
/// [`SpeedBound::next`] (docs/physics.md section 6), for frames `1..=frames`, as `(time s, speed ups)`.
pub fn bound_speed_profile(input: &ReportInput, frames: u64) -> Vec<(f64, f64)> {
    let scene = input.scene;
    let bound = SpeedBound::new(&scene.vars, scene.effects);
    let tau = scene.frame_time_s();
    let mut speed = scene.start.speed();
    let mut out = Vec::with_capacity(usize::try_from(frames).unwrap_or(0).saturating_add(1));
    out.push((0.0, speed));
    for k in 1..=frames {
        speed = bound.next(speed);
        out.push((k as f64 * tau, speed));
    }
    out
}

/// Figure 2: speed against time for each run, with the lower bound's speed profile.
pub fn speed_svg(input: &ReportInput) -> io::Result<String> {
    let tau = input.scene.frame_time_s();
    let t_end = end_time(input);
    let frames = ((t_end / tau).ceil() as u64).min(input.scene.max_frames);
    let profile = bound_speed_profile(input, frames);
    let series: Vec<Vec<(f64, f64)>> = input
        .runs
        .iter()
        .map(|r| {
            records(r.trace)
                .filter(|f| f.speed.is_finite())
                .map(|f| (f.time, f.speed))
                .collect()
        })
        .collect();
    let (_, y1) = value_range(
        series
            .iter()
            .flatten()
            .chain(profile.iter())
            .map(|p| p.1)
            .chain([0.0]),
        0.05,
    );
    let height = 420;
    svg_figure(height, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption("Speed against time", ("sans-serif", 20))
            .margin(MARGIN_PX)
            .x_label_area_size(X_LABEL_PX)
            .y_label_area_size(Y_LABEL_PX)
            .build_cartesian_2d(0.0..t_end * 1.02, 0.0..y1)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("speed (ups)")
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        for (i, (run, pts)) in input.runs.iter().zip(&series).enumerate() {
            let line = run_colour(i).stroke_width(2);
            chart
                .draw_series(LineSeries::new(thin(pts, MAX_POINTS_PER_SERIES), line))?
                .label(run.label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line));
            if let Some(c) = run.trace.crossing {
                chart.draw_series(DashedLineSeries::new(
                    [(c.time, 0.0), (c.time, y1)],
                    3,
                    3,
                    run_colour(i).stroke_width(1),
                ))?;
            }
        }
        // Drawn over the runs: greedy airstrafing follows it exactly.
        let bound_style = BOUND_COLOUR.stroke_width(2);
        chart
            .draw_series(DashedLineSeries::new(
                thin(&profile, MAX_POINTS_PER_SERIES),
                8,
                5,
                bound_style,
            ))?
            .label("lower bound's speed profile (greedy maximum)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], bound_style));
        let bt = input.bound.crossing.time;
        chart.draw_series(DashedLineSeries::new(
            [(bt, 0.0), (bt, y1)],
            3,
            3,
            BOUND_COLOUR.stroke_width(1),
        ))?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .draw()?;
        Ok(())
    })
}

/// `angle` wrapped into `(-180, 180]` degrees.
fn wrap_degrees(angle: f64) -> f64 {
    let a = (angle + 180.0).rem_euclid(360.0) - 180.0;
    if a <= -180.0 {
        a + 360.0
    } else {
        a
    }
}

/// Frames the turn rate is averaged over. Even, so the heading of a run that changes sides every frame
/// (a zigzag with a period of two frames) averages out; at 100 fps 0.08 s, at 66.67 ticks/s 0.12 s.
pub const TURN_RATE_WINDOW_FRAMES: usize = 8;

/// Below this speed, ups, the heading is not drawn: the direction of a velocity near zero is noise.
pub const HEADING_MIN_SPEED_UPS: f64 = 1.0;

/// The heading of the velocity (not the view) at the start and after each frame, degrees anticlockwise
/// from +x, as `(time s, degrees)`. The first is wrapped into `(-180, 180]`; each next one adds the
/// frame's turn of the velocity wrapped into `(-180, 180]`, so a run that goes round a hairpin reads 0 to
/// 180 and a run that alternates sides stays level (a velocity turns far less than half a turn in a frame;
/// the view does not, which is why the yaw is not plotted). Records slower than
/// [`HEADING_MIN_SPEED_UPS`] are left out.
pub fn heading_degrees(trace: &Trace) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut prev_raw: Option<f64> = None;
    for r in records(trace) {
        if !(r.vel.is_finite() && r.speed.is_finite() && r.speed >= HEADING_MIN_SPEED_UPS) {
            continue;
        }
        let raw = r.vel.angle().to_degrees();
        let heading = match (prev_raw, out.last()) {
            (Some(p), Some(&(_, h))) => h + wrap_degrees(raw - p),
            _ => wrap_degrees(raw),
        };
        prev_raw = Some(raw);
        out.push((r.time, heading));
    }
    out
}

/// The turn rate of the velocity's heading, degrees per second (positive: anticlockwise, to the left),
/// averaged over [`TURN_RATE_WINDOW_FRAMES`] frames: for each window of that many frames of
/// [`heading_degrees`], the heading's change over the window's time, at the window's middle time.
/// Empty when the run has fewer headings than a window.
pub fn turn_rate_deg_per_s(trace: &Trace) -> Vec<(f64, f64)> {
    heading_degrees(trace)
        .windows(TURN_RATE_WINDOW_FRAMES + 1)
        .filter_map(|w| {
            let (first, last) = (w[0], w[TURN_RATE_WINDOW_FRAMES]);
            let dt = last.0 - first.0;
            (dt > 0.0).then(|| (0.5 * (first.0 + last.0), (last.1 - first.1) / dt))
        })
        .collect()
}

/// The clearance of the hull to the nearest wall or rule line at the start and after each frame, as
/// `(time s, units)`; negative when overlapping. Left empty when the scene has no walls (infinite
/// clearance). Its minimum is [`Trace::min_clearance`].
pub fn clearance_series(trace: &Trace) -> Vec<(f64, f64)> {
    records(trace)
        .filter(|r| r.clearance.is_finite())
        .map(|r| (r.time, r.clearance))
        .collect()
}

/// One line per run of `data` on `chart`, in the runs' colours, labelled.
fn draw_run_lines(chart: &mut Chart, input: &ReportInput, data: &[Vec<(f64, f64)>]) -> Draw {
    for (i, (run, pts)) in input.runs.iter().zip(data).enumerate() {
        let line = run_colour(i).stroke_width(2);
        chart
            .draw_series(LineSeries::new(thin(pts, MAX_POINTS_PER_SERIES), line))?
            .label(run.label)
            .legend(line_legend(line));
    }
    Ok(())
}

/// A thin grey horizontal line at `y` across `x`.
fn draw_level(chart: &mut Chart, x: (f64, f64), y: f64) -> Draw {
    chart.draw_series(LineSeries::new(
        [(x.0, y), (x.1, y)],
        BOUND_COLOUR.stroke_width(1),
    ))?;
    Ok(())
}

/// Figure 3: where the runs are heading and how fast they turn: the velocity's heading (top, degrees,
/// [`heading_degrees`]) and its turn rate averaged over [`TURN_RATE_WINDOW_FRAMES`] frames (bottom,
/// degrees per second, [`turn_rate_deg_per_s`]), against time.
pub fn heading_svg(input: &ReportInput) -> io::Result<String> {
    let t_end = end_time(input) * 1.02;
    let headings: Vec<Vec<(f64, f64)>> = input
        .runs
        .iter()
        .map(|r| heading_degrees(r.trace))
        .collect();
    let rates: Vec<Vec<(f64, f64)>> = input
        .runs
        .iter()
        .map(|r| turn_rate_deg_per_s(r.trace))
        .collect();
    let heading_range = value_range(headings.iter().flatten().map(|p| p.1), 0.08);
    // Zero is always on the turn-rate axis: a straight run reads as a line on it.
    let rate_range = value_range(rates.iter().flatten().map(|p| p.1).chain([0.0]), 0.08);
    let rate_title =
        format!("Turn rate of the velocity, averaged over {TURN_RATE_WINDOW_FRAMES} frames");
    svg_figure(640, |root| {
        let panels = root.split_evenly((2, 1));
        let specs = [
            (
                "Heading of the velocity against time",
                "heading (degrees)",
                &headings,
                heading_range,
                None,
            ),
            (
                rate_title.as_str(),
                "turn rate (degrees/s, + left)",
                &rates,
                rate_range,
                Some(0.0),
            ),
        ];
        for (panel, (title, y_desc, data, (ylo, yhi), level)) in panels.iter().zip(specs) {
            let mut chart = ChartBuilder::on(panel)
                .caption(title, ("sans-serif", 18))
                .margin(MARGIN_PX)
                .x_label_area_size(X_LABEL_PX)
                .y_label_area_size(Y_LABEL_PX)
                .build_cartesian_2d(0.0..t_end, ylo..yhi)?;
            draw_axes(&mut chart, "time (s)", y_desc)?;
            if let Some(y) = level {
                draw_level(&mut chart, (0.0, t_end), y)?;
            }
            draw_run_lines(&mut chart, input, data)?;
            draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    })
}

/// Figure 4: the clearance of the hull to the nearest wall or rule line along each run
/// ([`clearance_series`]), units against time, with each run's minimum marked and labelled and a grey
/// line at zero (touching).
pub fn clearance_svg(input: &ReportInput) -> io::Result<String> {
    let t_end = end_time(input) * 1.02;
    let series: Vec<Vec<(f64, f64)>> = input
        .runs
        .iter()
        .map(|r| clearance_series(r.trace))
        .collect();
    let (ylo, yhi) = value_range(series.iter().flatten().map(|p| p.1).chain([0.0]), 0.08);
    svg_figure(420, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Clearance to the nearest wall or rule line against time",
                ("sans-serif", 20),
            )
            .margin(MARGIN_PX)
            .x_label_area_size(X_LABEL_PX)
            .y_label_area_size(Y_LABEL_PX)
            .build_cartesian_2d(0.0..t_end, ylo..yhi)?;
        draw_axes(&mut chart, "time (s)", "clearance (units)")?;
        draw_level(&mut chart, (0.0, t_end), 0.0)?;
        draw_run_lines(&mut chart, input, &series)?;
        for (i, (run, pts)) in input.runs.iter().zip(&series).enumerate() {
            let Some(&(t, c)) = pts.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
                continue;
            };
            let colour = run_colour(i);
            // The label above the point, on the side with room; later runs' labels higher, so two minima
            // at one time stay readable.
            let right_half = t > 0.5 * t_end;
            let (dx, h_pos) = if right_half {
                (-8, HPos::Right)
            } else {
                (8, HPos::Left)
            };
            let dy = -8 - 16 * i32::try_from(i).unwrap_or(0);
            let font = ("sans-serif", 13)
                .into_font()
                .color(&colour)
                .pos(Pos::new(h_pos, VPos::Bottom));
            chart.draw_series([EmptyElement::at((t, c))
                + Circle::new((0, 0), 4, colour.filled())
                + Text::new(
                    format!("{}: min {c:.4} units at {t:.3} s", run.label),
                    (dx, dy),
                    font,
                )])?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
    })
}

/// The radius of the circle through each frame's position and its neighbours' (docs/physics.md section 9),
/// against the speed at the middle position, as `(speed ups, radius units)`; straight stretches (infinite
/// radius) are left out.
pub fn turn_radii(trace: &Trace) -> Vec<(f64, f64)> {
    let recs: Vec<&FrameRecord> = records(trace).collect();
    recs.windows(3)
        .filter_map(|w| {
            let r = circumradius(w[0].pos, w[1].pos, w[2].pos);
            (r.is_finite() && r > 0.0 && w[1].speed.is_finite() && w[1].speed > 0.0)
                .then_some((w[1].speed, r))
        })
        .collect()
}

/// The radius figure's axes: the speeds shown, the radii shown (log scale), and the section-9 relations of
/// maximum-acceleration airstrafing sampled over those speeds as `(speed, source text's, first order)`.
struct RadiusAxes {
    speed: (f64, f64),
    radius: (f64, f64),
    relations: Vec<(f64, f64, f64)>,
}

/// Axes that hold the runs' radii `points` and the relations; without points, speeds from the max speed to
/// three times it.
fn radius_axes(vars: &MovementVars, points: &[Vec<(f64, f64)>]) -> RadiusAxes {
    let (mut v_lo, mut v_hi) = value_range(points.iter().flatten().map(|p| p.0), 0.0);
    if points.iter().all(Vec::is_empty) {
        (v_lo, v_hi) = (vars.maxspeed, 3.0 * vars.maxspeed);
    }
    let v_lo = v_lo.max(1.0);
    let v_hi = v_hi.max(v_lo + 1.0);
    let relations: Vec<(f64, f64, f64)> = (0..=RELATION_SAMPLES)
        .map(|k| {
            let v = v_lo + (v_hi - v_lo) * k as f64 / RELATION_SAMPLES as f64;
            let r = max_accel_radii(vars, v);
            (v, r.source_text, r.first_order)
        })
        .collect();
    let relation_radii = || relations.iter().flat_map(|r| [r.1, r.2]);
    let relation_max = relation_radii()
        .filter(|r| r.is_finite())
        .fold(0.0, f64::max);
    let relation_min = relation_radii()
        .filter(|r| r.is_finite() && *r > 0.0)
        .fold(f64::INFINITY, f64::min);
    let data_min = points
        .iter()
        .flatten()
        .map(|p| p.1)
        .fold(f64::INFINITY, f64::min);
    let data_max = points.iter().flatten().map(|p| p.1).fold(0.0, f64::max);
    // Nearly straight frames have radii of millions of units: show up to 1000 times the relations'.
    let cap = if relation_max > 0.0 {
        1000.0 * relation_max
    } else {
        1e6
    };
    let r_lo = (data_min.min(relation_min) * 0.8).clamp(1e-3, 1e9);
    let r_hi = (data_max.max(relation_max).min(cap) * 1.25).max(r_lo * 10.0);
    RadiusAxes {
        speed: (v_lo, v_hi),
        radius: (r_lo, r_hi),
        relations,
    }
}

/// Figure 5: the turn radius of every frame against speed (log scale), with the section-9 relations of
/// maximum-acceleration airstrafing drawn over it: the source text's relation and the first-order radius
/// `tau |v'|^2 / (mu sin theta)` (which the circle through three simulated positions follows).
pub fn radius_svg(input: &ReportInput) -> io::Result<String> {
    let points: Vec<Vec<(f64, f64)>> = input.runs.iter().map(|r| turn_radii(r.trace)).collect();
    let RadiusAxes {
        speed: (v_lo, v_hi),
        radius: (r_lo, r_hi),
        relations,
    } = radius_axes(&input.scene.vars, &points);
    let x_pad = 0.03 * (v_hi - v_lo);
    svg_figure(520, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Turn radius per frame against speed (docs/physics.md section 9)",
                ("sans-serif", 20),
            )
            .margin(MARGIN_PX)
            .x_label_area_size(X_LABEL_PX)
            .y_label_area_size(Y_LABEL_PX)
            .build_cartesian_2d((v_lo - x_pad)..(v_hi + x_pad), (r_lo..r_hi).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("speed (ups)")
            .y_desc("radius (units, log scale)")
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        let source = RGBColor(148, 0, 160).stroke_width(2);
        chart
            .draw_series(DashedLineSeries::new(
                relations
                    .iter()
                    .filter(|r| r.1.is_finite() && r.1 <= r_hi)
                    .map(|r| (r.0, r.1))
                    .collect::<Vec<_>>(),
                8,
                5,
                source,
            ))?
            .label("source text's relation, maximum-acceleration airstrafe")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], source));
        let first = BLACK.stroke_width(1);
        chart
            .draw_series(LineSeries::new(
                relations
                    .iter()
                    .filter(|r| r.2.is_finite() && r.2 <= r_hi)
                    .map(|r| (r.0, r.2))
                    .collect::<Vec<_>>(),
                first,
            ))?
            .label("first order tau v'^2/(mu sin theta) (measured)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], first));
        // The runs' radii over the curves: they fall on the first-order one.
        for (i, (run, pts)) in input.runs.iter().zip(&points).enumerate() {
            let colour = run_colour(i);
            let shown: Vec<(f64, f64)> = pts.iter().copied().filter(|p| p.1 <= r_hi).collect();
            let style = colour.mix(0.6).filled();
            chart
                .draw_series(
                    thin(&shown, MAX_POINTS_PER_SERIES)
                        .into_iter()
                        .map(|p| Circle::new(p, 2, style)),
                )?
                .label(format!("{}: circle through 3 positions", run.label))
                .legend(move |(x, y)| Circle::new((x + 10, y), 3, style));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .draw()?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_ends_and_bounds_the_count() {
        let v: Vec<u32> = (0..10_001).collect();
        let t = thin(&v, 2000);
        assert!(t.len() <= 2001, "{}", t.len());
        assert_eq!(t.first(), Some(&0));
        assert_eq!(t.last(), Some(&10_000));
        assert_eq!(thin(&v[..5], 2000), vec![0, 1, 2, 3, 4]);
    }

    fn record(frame: u64, heading_deg: f64, speed: f64) -> FrameRecord {
        let vel = Vec2::new(
            heading_deg.to_radians().cos(),
            heading_deg.to_radians().sin(),
        ) * speed;
        FrameRecord {
            frame,
            time: frame as f64 * 0.01,
            pos: Vec2::ZERO,
            vel,
            speed,
            // The view swings half a turn every frame, as it does when sides alternate.
            yaw_rad: (180.0 * frame as f64).to_radians(),
            theta_rad: 0.0,
            on_ground: false,
            ducked: false,
            clearance: 10.0 - frame as f64,
            contacts: 0,
            broke_rule: false,
        }
    }

    fn trace_of(headings_deg: &[f64], speed: f64) -> Trace {
        Trace {
            controller: "test".to_string(),
            start: record(0, headings_deg[0], speed),
            frames: headings_deg[1..]
                .iter()
                .enumerate()
                .map(|(k, &h)| record(k as u64 + 1, h, speed))
                .collect(),
            controls: Vec::new(),
            crossing: None,
            numerical_failure: false,
            interrupted: false,
        }
    }

    #[test]
    fn heading_is_continuous_through_the_back_direction() {
        let t = trace_of(&[170.0, -170.0, -150.0], 300.0);
        let h: Vec<f64> = heading_degrees(&t).iter().map(|p| p.1).collect();
        assert_eq!(h.len(), 3);
        assert!(
            (h[0] - 170.0).abs() < 1e-9
                && (h[1] - 190.0).abs() < 1e-9
                && (h[2] - 210.0).abs() < 1e-9,
            "{h:?}"
        );
    }

    #[test]
    fn turn_rate_of_a_steady_turn_and_of_a_zigzag() {
        // 0.5 degrees a frame at 100 fps: 50 degrees per second, whatever the window.
        let steady: Vec<f64> = (0..40).map(|k| 0.5 * k as f64).collect();
        let rates = turn_rate_deg_per_s(&trace_of(&steady, 300.0));
        assert_eq!(rates.len(), 40 - TURN_RATE_WINDOW_FRAMES);
        assert!(rates.iter().all(|r| (r.1 - 50.0).abs() < 1e-9), "{rates:?}");
        // Sides alternating every frame: the heading zigzags by 2 degrees and the average turn is zero.
        let zigzag: Vec<f64> = (0..40)
            .map(|k| if k % 2 == 0 { 0.0 } else { 2.0 })
            .collect();
        let rates = turn_rate_deg_per_s(&trace_of(&zigzag, 300.0));
        assert!(rates.iter().all(|r| r.1.abs() < 1e-9), "{rates:?}");
    }

    #[test]
    fn slow_records_have_no_heading() {
        let mut t = trace_of(&[0.0, 10.0, 20.0], 300.0);
        t.start.speed = 0.5 * HEADING_MIN_SPEED_UPS;
        t.start.vel = Vec2::new(t.start.speed, 0.0);
        let h = heading_degrees(&t);
        assert_eq!(h.len(), 2);
        assert!((h[0].1 - 10.0).abs() < 1e-9, "{h:?}");
    }

    #[test]
    fn clearance_series_has_the_start_and_every_frame() {
        let t = trace_of(&[0.0; 5], 300.0);
        let c = clearance_series(&t);
        assert_eq!(c.len(), 5);
        let min = c.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        assert_eq!(min, t.min_clearance());
    }
}
