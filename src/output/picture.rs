//! Cross-section and history pictures (PNG, embedded font).
//!
//! Text uses DejaVu Sans, embedded in the binary (crate `dejavu`) and registered with plotters'
//! ab_glyph renderer as "sans-serif", so no system fonts are needed.

// `crate::Error` is large (its `Deck` variant); boxing it is the error module's decision.
#![allow(clippy::result_large_err)]

use std::collections::HashMap;
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::case::{ColorBy, PictureSpec};
use crate::error::{Error, Result};
use crate::particles::Particles;
use crate::tensor;

/// The particles of one cross-section at one time, ready to draw.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SectionFrame {
    /// Time (s).
    pub time: f64,
    /// In-plane coordinates (m).
    pub points: Vec<[f64; 2]>,
    /// Colour value per point (see [`extract_section`]).
    pub values: Vec<f64>,
    /// Body index per point.
    pub bodies: Vec<u32>,
}

/// The two in-plane axes of a section with normal `normal` (3D): normal x → (y, z),
/// normal y → (x, z), normal z → (x, y). In 2D always (x, y).
pub fn in_plane_axes(dimension: usize, normal: usize) -> [usize; 2] {
    if dimension < 3 {
        return [0, 1];
    }
    match normal {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

/// The value a picture colours particle `i` by.
fn color_value<const D: usize>(p: &Particles<D>, i: usize, color_by: ColorBy) -> f64 {
    match color_by {
        ColorBy::Body => p.body[i] as f64,
        ColorBy::Pressure => p.p[i],
        ColorBy::PlasticStrain => p.eps_p[i],
        ColorBy::Damage => p.damage[i],
        ColorBy::Velocity => p.v[i].norm(),
        ColorBy::Density => p.rho[i],
        ColorBy::VonMises => tensor::von_mises(&p.s[i].full()),
    }
}

/// Particles in the slab |x_normal − position| < thickness/2 (3D); all real particles in 2D.
/// Points are the two in-plane coordinates (for normal y in 3D: (x, z); normal x: (y, z);
/// normal z: (x, y)); values per ColorBy (Body: body index as f64; Pressure; PlasticStrain;
/// Velocity: |v|; Density; VonMises).
pub fn extract_section<const D: usize>(
    particles: &Particles<D>,
    time: f64,
    spec: &PictureSpec,
    thickness: f64,
) -> SectionFrame {
    let [a, b] = in_plane_axes(D, spec.normal_axis);
    let normal = spec.normal_axis.min(D.saturating_sub(1));
    let half = 0.5 * thickness;
    let n = particles.n_real.min(particles.len());
    let mut frame = SectionFrame {
        time,
        ..Default::default()
    };
    for i in 0..n {
        let x = &particles.x[i];
        if D >= 3 && (x[normal] - spec.position).abs() >= half {
            continue;
        }
        frame.points.push([x[a], x[b]]);
        frame.values.push(color_value(particles, i, spec.color_by));
        frame.bodies.push(particles.body[i]);
    }
    frame
}

// ---------------------------------------------------------------------------------------------
// Fonts, colours, errors.

const FONT: &str = "sans-serif";

/// Register the embedded DejaVu Sans as plotters' "sans-serif" (once per process).
fn register_fonts() -> Result<()> {
    static OK: OnceLock<bool> = OnceLock::new();
    let ok = *OK.get_or_init(|| {
        use plotters::style::register_font;
        register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
            && register_font(FONT, FontStyle::Bold, dejavu::sans::bold()).is_ok()
            && register_font(FONT, FontStyle::Oblique, dejavu::sans::oblique()).is_ok()
            && register_font(FONT, FontStyle::Italic, dejavu::sans::oblique()).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Invalid(
            "the embedded DejaVu Sans font could not be loaded".into(),
        ))
    }
}

/// Create (truncate) the output file first, so that an unwritable path is an I/O error naming
/// the path rather than a drawing error at the end.
fn check_writable(path: &Path) -> Result<()> {
    std::fs::File::create(path)
        .map(drop)
        .map_err(|e| Error::io(path, e))
}

fn draw_err<E: std::fmt::Debug>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| {
        Error::Invalid(format!(
            "{}: drawing the picture failed: {e:?}",
            path.display()
        ))
    }
}

/// Viridis, sampled at 9 evenly spaced stops (matplotlib's table).
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (72, 40, 120),
    (62, 74, 137),
    (49, 104, 142),
    (38, 130, 142),
    (31, 158, 137),
    (53, 183, 121),
    (109, 205, 89),
    (253, 231, 37),
];

/// Viridis colour at `t` in [0, 1] (clamped), linear between stops.
pub fn viridis(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let s = t * (VIRIDIS.len() - 1) as f64;
    let k = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let f = s - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    let mix = |x: u8, y: u8| (x as f64 + f * (y as f64 - x as f64)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Distinct colours for bodies and series (Tableau 10).
const PALETTE: [RGBColor; 10] = [
    RGBColor(78, 121, 167),
    RGBColor(242, 142, 43),
    RGBColor(225, 87, 89),
    RGBColor(118, 183, 178),
    RGBColor(89, 161, 79),
    RGBColor(237, 201, 72),
    RGBColor(176, 122, 161),
    RGBColor(255, 157, 167),
    RGBColor(156, 117, 95),
    RGBColor(186, 176, 172),
];

fn palette(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

const NAN_COLOR: RGBColor = RGBColor(200, 200, 200);
const AXIS_COLOR: RGBColor = RGBColor(40, 40, 40);

/// A round tick step near `range / target`: 1, 2, 2.5 or 5 × 10^k.
fn nice_step(range: f64, target: usize) -> f64 {
    let raw = (range / target.max(1) as f64).abs();
    if raw <= 0.0 || !raw.is_finite() {
        return 1.0;
    }
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 2.5 {
        2.5
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// Format `v` for a scale whose ticks are `step` apart.
fn fmt_tick(v: f64, step: f64) -> String {
    let v = if v.abs() < step * 1e-9 { 0.0 } else { v };
    let mag = step.abs().log10().floor();
    let big = v.abs().max(step.abs());
    if big >= 1e6 || (big < 1e-3 && big > 0.0) {
        let decimals = ((big.log10().floor() - mag).max(0.0) as usize).min(6);
        format!("{v:.decimals$e}")
    } else {
        // 2.5 × 10^k steps need one more decimal than 10^k.
        let mut decimals = (-mag).max(0.0) as usize;
        if (step / 10f64.powf(mag) - 2.5).abs() < 1e-9 {
            decimals += 1;
        }
        format!("{v:.decimals$}")
    }
}

/// Ticks covering [lo, hi].
fn ticks(lo: f64, hi: f64, target: usize) -> (Vec<f64>, f64) {
    let step = nice_step(hi - lo, target);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    let ticks = (first..=last).take(100).map(|k| k as f64 * step).collect();
    (ticks, step)
}

// ---------------------------------------------------------------------------------------------
// Cross sections.

/// Margin around each panel's chart (px).
const MARGIN: u32 = 12;
/// Strip above each panel for its caption (px).
const CAPTION_H: u32 = 36;
/// Label areas of each panel (px).
const X_LABEL_H: u32 = 52;
const Y_LABEL_W: u32 = 66;
/// Largest and smallest plot area of a panel (px).
const PLOT_MAX: (f64, f64) = (560.0, 440.0);
const PLOT_MIN: f64 = 140.0;
/// Width of the legend / colour-bar column on the right (px).
const SIDE_W: u32 = 230;

/// Axis limits (mm) and plot-area size (px) shared by all panels, with equal scales on both
/// axes.
#[derive(Debug, Clone, Copy)]
struct SectionLayout {
    x: (f64, f64),
    y: (f64, f64),
    plot_w: u32,
    plot_h: u32,
    /// Typical particle spacing (mm), if there are points.
    spacing: Option<f64>,
}

impl SectionLayout {
    fn new(frames: &[SectionFrame]) -> Self {
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in frames.iter().flat_map(|f| &f.points) {
            if p[0].is_finite() && p[1].is_finite() {
                x0 = x0.min(p[0] * 1e3);
                x1 = x1.max(p[0] * 1e3);
                y0 = y0.min(p[1] * 1e3);
                y1 = y1.max(p[1] * 1e3);
            }
        }
        if x0 > x1 {
            (x0, x1, y0, y1) = (-1.0, 1.0, -1.0, 1.0);
        }
        // The median over frames of the typical spacing (mm).
        let mut spacings: Vec<f64> = frames
            .iter()
            .filter_map(|f| typical_spacing(&f.points))
            .map(|s| s * 1e3)
            .collect();
        spacings.sort_by(|a, b| a.total_cmp(b));
        let spacing = spacings.get(spacings.len() / 2).copied();
        // Give a degenerate extent a size; pad by 4 % and at least one spacing, so that the
        // markers stay inside the frame.
        let span = (x1 - x0).max(y1 - y0).max(1e-9);
        let dx = (x1 - x0).max(0.02 * span);
        let dy = (y1 - y0).max(0.02 * span);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let pad = spacing.unwrap_or(0.0);
        let dx = (dx * 1.08).max(dx + 2.0 * pad);
        let dy = (dy * 1.08).max(dy + 2.0 * pad);

        let aspect = dx / dy;
        let (w, h) = if aspect >= PLOT_MAX.0 / PLOT_MAX.1 {
            (PLOT_MAX.0, (PLOT_MAX.0 / aspect).max(PLOT_MIN))
        } else {
            ((PLOT_MAX.1 * aspect).max(PLOT_MIN), PLOT_MAX.1)
        };
        let (plot_w, plot_h) = (w.round() as u32, h.round() as u32);
        // Equal scale (mm per px) on both axes.
        let scale = (dx / plot_w as f64).max(dy / plot_h as f64);
        let (hx, hy) = (0.5 * scale * plot_w as f64, 0.5 * scale * plot_h as f64);
        SectionLayout {
            x: (cx - hx, cx + hx),
            y: (cy - hy, cy + hy),
            plot_w,
            plot_h,
            spacing,
        }
    }

    /// mm per pixel.
    fn scale(&self) -> f64 {
        (self.x.1 - self.x.0) / self.plot_w as f64
    }

    fn panel_w(&self) -> u32 {
        self.plot_w + Y_LABEL_W + 2 * MARGIN
    }

    fn size(&self, frames: usize) -> (u32, u32) {
        (
            frames.max(1) as u32 * self.panel_w() + SIDE_W,
            CAPTION_H + self.plot_h + X_LABEL_H + 2 * MARGIN,
        )
    }
}

/// Pixel size (width, height) of the picture [`draw_sections`] makes of `frames`: one panel per
/// frame, `Y_LABEL_W + 2·MARGIN` px wider than its plot area, plus a 230 px legend column.
pub fn section_image_size(frames: &[SectionFrame]) -> (u32, u32) {
    SectionLayout::new(frames).size(frames.len())
}

/// Typical distance between neighbouring points: the median nearest-neighbour distance of up
/// to 2000 sampled points (grid hashing). None with fewer than two distinct points.
fn typical_spacing(points: &[[f64; 2]]) -> Option<f64> {
    let pts: Vec<[f64; 2]> = points
        .iter()
        .copied()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in &pts {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let n = pts.len() as f64;
    let area = (x1 - x0) * (y1 - y0);
    let cell = if area > 0.0 {
        (area / n).sqrt()
    } else {
        (x1 - x0).max(y1 - y0) / n
    };
    if cell <= 0.0 || !cell.is_finite() {
        return None;
    }
    let key = |p: &[f64; 2]| {
        (
            ((p[0] - x0) / cell).floor() as i64,
            ((p[1] - y0) / cell).floor() as i64,
        )
    };
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, p) in pts.iter().enumerate() {
        grid.entry(key(p)).or_default().push(i);
    }
    let stride = (pts.len() / 2000).max(1);
    let mut nearest = Vec::new();
    for i in (0..pts.len()).step_by(stride) {
        let p = pts[i];
        let (ci, cj) = key(&p);
        let mut best = f64::MAX;
        for ring in 1..=4i64 {
            for di in -ring..=ring {
                for dj in -ring..=ring {
                    if di.abs() != ring && dj.abs() != ring && ring > 1 {
                        continue; // inner cells were searched with the previous ring
                    }
                    if let Some(list) = grid.get(&(ci + di, cj + dj)) {
                        for &k in list {
                            let d =
                                ((pts[k][0] - p[0]).powi(2) + (pts[k][1] - p[1]).powi(2)).sqrt();
                            if d > 0.0 && d < best {
                                best = d;
                            }
                        }
                    }
                }
            }
            // Points in cells beyond `ring` are farther than ring·cell.
            if best <= ring as f64 * cell {
                break;
            }
        }
        if best < f64::MAX {
            nearest.push(best);
        }
    }
    if nearest.is_empty() {
        return None;
    }
    nearest.sort_by(|a, b| a.total_cmp(b));
    Some(nearest[nearest.len() / 2])
}

/// Quantity, display unit and scale factor from SI for a colour field.
fn field_unit(color_by: ColorBy, max_abs: f64) -> (&'static str, &'static str, f64) {
    match color_by {
        ColorBy::Body => ("body", "", 1.0),
        ColorBy::Pressure | ColorBy::VonMises => {
            let name = if color_by == ColorBy::Pressure {
                "pressure"
            } else {
                "von Mises stress"
            };
            if max_abs >= 1e9 {
                (name, "GPa", 1e-9)
            } else {
                (name, "MPa", 1e-6)
            }
        }
        ColorBy::PlasticStrain => ("plastic strain", "–", 1.0),
        ColorBy::Damage => ("damage", "–", 1.0),
        ColorBy::Velocity => ("speed |v|", "m/s", 1.0),
        ColorBy::Density => ("density", "kg/m³", 1.0),
    }
}

fn text_style(size: f64) -> TextStyle<'static> {
    (FONT, size).into_font().color(&AXIS_COLOR)
}

/// One PNG with the frames side by side (one panel per frame, same axes limits and colour scale
/// for all), axes in mm labelled "`axis_labels[k]` (mm)", each panel titled with its time in μs;
/// coloured by body (distinct colours, legend with `body_names`) or by a field (viridis, with a
/// colour bar giving its range and unit). Points with a non-finite value are grey.
pub fn draw_sections(
    path: &Path,
    frames: &[SectionFrame],
    color_by: ColorBy,
    body_names: &[String],
    axis_labels: [&str; 2],
) -> Result<()> {
    if frames.is_empty() {
        return Err(Error::Invalid(format!(
            "{}: no section frames to draw",
            path.display()
        )));
    }
    for f in frames {
        if f.points.len() != f.values.len() || f.points.len() != f.bodies.len() {
            return Err(Error::Invalid(format!(
                "{}: section frame at t = {} s has {} points, {} values, {} bodies",
                path.display(),
                f.time,
                f.points.len(),
                f.values.len(),
                f.bodies.len()
            )));
        }
    }
    register_fonts()?;
    check_writable(path)?;
    let err = draw_err(path);

    let layout = SectionLayout::new(frames);
    let (width, height) = layout.size(frames.len());

    // Colour scale shared by all panels (display units).
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for &v in frames.iter().flat_map(|f| &f.values) {
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if lo > hi {
        (lo, hi) = (0.0, 1.0);
    }
    let (quantity, unit, factor) = field_unit(color_by, lo.abs().max(hi.abs()));
    let (mut lo, mut hi) = (lo * factor, hi * factor);
    if hi - lo <= 1e-12 * lo.abs().max(hi.abs()) {
        let d = if lo == 0.0 { 1.0 } else { 0.05 * lo.abs() };
        lo -= d;
        hi += d;
    }
    let color_of = |value: f64, body: u32| -> RGBColor {
        match color_by {
            ColorBy::Body => palette(body as usize),
            _ if !value.is_finite() => NAN_COLOR,
            _ => viridis((value * factor - lo) / (hi - lo)),
        }
    };

    // Marker size from the particle spacing on the picture.
    let spacing_px = layout
        .spacing
        .map(|s| s / layout.scale())
        .unwrap_or(4.0)
        .clamp(1.0, 60.0);

    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let (panels, side) = root.split_horizontally(frames.len() as u32 * layout.panel_w());
    let panel_areas = panels.split_evenly((1, frames.len()));

    let (_, xstep) = ticks(layout.x.0, layout.x.1, 6);
    let (_, ystep) = ticks(layout.y.0, layout.y.1, 6);
    let x_desc = format!("{} (mm)", axis_labels[0]);
    let y_desc = format!("{} (mm)", axis_labels[1]);

    for (frame, area) in frames.iter().zip(&panel_areas) {
        let (caption, body) = area.split_vertically(CAPTION_H);
        caption
            .draw(&Text::new(
                format!("t = {:.2} μs", frame.time * 1e6),
                (
                    (MARGIN + Y_LABEL_W + layout.plot_w / 2) as i32,
                    (CAPTION_H / 2 + 4) as i32,
                ),
                (FONT, 19.0)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Center, VPos::Center)),
            ))
            .map_err(&err)?;

        let mut chart = ChartBuilder::on(&body)
            .margin(MARGIN)
            .x_label_area_size(X_LABEL_H)
            .y_label_area_size(Y_LABEL_W)
            .build_cartesian_2d(layout.x.0..layout.x.1, layout.y.0..layout.y.1)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(7)
            .y_labels(7)
            .x_desc(x_desc.as_str())
            .y_desc(y_desc.as_str())
            .x_label_formatter(&|v| fmt_tick(*v, xstep))
            .y_label_formatter(&|v| fmt_tick(*v, ystep))
            .label_style(text_style(14.0))
            .axis_desc_style(text_style(16.0))
            .axis_style(AXIS_COLOR)
            .draw()
            .map_err(&err)?;

        let pts = frame
            .points
            .iter()
            .zip(&frame.values)
            .zip(&frame.bodies)
            .filter(|((p, _), _)| p[0].is_finite() && p[1].is_finite())
            .map(|((p, &v), &b)| ((p[0] * 1e3, p[1] * 1e3), color_of(v, b)));
        if spacing_px >= 2.8 {
            // Filled discs of diameter √2 × spacing: they cover a square lattice without gaps,
            // so that a body looks solid.
            let r = (0.72 * spacing_px).ceil().max(1.0) as u32;
            chart
                .draw_series(
                    pts.map(|(c, col)| EmptyElement::at(c) + Circle::new((0, 0), r, col.filled())),
                )
                .map_err(&err)?;
        } else {
            // Dense: squares of ⌈spacing⌉ px.
            let s = spacing_px.ceil().max(1.0) as i32;
            let a = -(s / 2);
            chart
                .draw_series(pts.map(|(c, col)| {
                    EmptyElement::at(c) + Rectangle::new([(a, a), (a + s, a + s)], col.filled())
                }))
                .map_err(&err)?;
        }
        // Frame around the plot area.
        chart
            .plotting_area()
            .draw(&Rectangle::new(
                [(layout.x.0, layout.y.0), (layout.x.1, layout.y.1)],
                AXIS_COLOR.stroke_width(1),
            ))
            .map_err(&err)?;
    }

    let top = (CAPTION_H + MARGIN) as i32;
    if color_by == ColorBy::Body {
        draw_body_legend(&side, frames, body_names, top).map_err(&err)?;
    } else {
        let label = if unit.is_empty() {
            quantity.to_string()
        } else {
            format!("{quantity} ({unit})")
        };
        draw_colour_bar(&side, &label, (lo, hi), top, layout.plot_h as i32).map_err(&err)?;
    }
    root.present().map_err(&err)?;
    Ok(())
}

type AreaResult<'a> =
    std::result::Result<(), DrawingAreaErrorKind<<BitMapBackend<'a> as DrawingBackend>::ErrorType>>;

fn draw_body_legend<'a>(
    side: &DrawingArea<BitMapBackend<'a>, Shift>,
    frames: &[SectionFrame],
    body_names: &[String],
    top: i32,
) -> AreaResult<'a> {
    let mut bodies: Vec<u32> = frames
        .iter()
        .flat_map(|f| f.bodies.iter().copied())
        .collect();
    bodies.sort_unstable();
    bodies.dedup();
    side.draw(&Text::new(
        "bodies",
        (16, (CAPTION_H / 2 + 4) as i32),
        (FONT, 17.0)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center)),
    ))?;
    let max_rows = 40;
    for (row, &b) in bodies.iter().take(max_rows).enumerate() {
        let y = top + 8 + 26 * row as i32;
        side.draw(&Rectangle::new(
            [(16, y - 8), (32, y + 8)],
            palette(b as usize).filled(),
        ))?;
        side.draw(&Rectangle::new(
            [(16, y - 8), (32, y + 8)],
            AXIS_COLOR.stroke_width(1),
        ))?;
        let mut name = body_names
            .get(b as usize)
            .cloned()
            .unwrap_or_else(|| format!("body {b}"));
        if name.chars().count() > 22 {
            name = name.chars().take(21).collect::<String>() + "…";
        }
        side.draw(&Text::new(
            name,
            (40, y),
            text_style(15.0).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    if bodies.len() > max_rows {
        let y = top + 8 + 26 * max_rows as i32;
        side.draw(&Text::new(
            format!("… {} more", bodies.len() - max_rows),
            (40, y),
            text_style(15.0).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    Ok(())
}

fn draw_colour_bar<'a>(
    side: &DrawingArea<BitMapBackend<'a>, Shift>,
    label: &str,
    (lo, hi): (f64, f64),
    top: i32,
    height: i32,
) -> AreaResult<'a> {
    let (x0, x1) = (18, 44);
    side.draw(&Text::new(
        label.to_string(),
        (10, (CAPTION_H / 2 + 4) as i32),
        (FONT, 17.0)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center)),
    ))?;
    let bottom = top + height;
    for y in top..bottom {
        let t = (bottom - 1 - y) as f64 / (height - 1).max(1) as f64;
        side.draw(&Rectangle::new([(x0, y), (x1, y + 1)], viridis(t).filled()))?;
    }
    side.draw(&Rectangle::new(
        [(x0, top), (x1, bottom)],
        AXIS_COLOR.stroke_width(1),
    ))?;
    let (tv, step) = ticks(lo, hi, 6);
    let y_of = |v: f64| bottom as f64 - (v - lo) / (hi - lo) * height as f64;
    for v in tv {
        let y = y_of(v).round() as i32;
        side.draw(&PathElement::new(
            vec![(x1, y), (x1 + 5, y)],
            AXIS_COLOR.stroke_width(1),
        ))?;
        side.draw(&Text::new(
            fmt_tick(v, step),
            (x1 + 9, y),
            text_style(14.0).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    // The exact range, below the bar.
    let sig = |v: f64| {
        format!("{v:.4}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    };
    let range = if lo.abs().max(hi.abs()) >= 1e5 || lo.abs().max(hi.abs()) < 1e-2 {
        format!("range {lo:.3e} … {hi:.3e}")
    } else {
        format!("range {} … {}", sig(lo), sig(hi))
    };
    side.draw(&Text::new(
        range,
        (10, bottom + 26),
        text_style(13.0).pos(Pos::new(HPos::Left, VPos::Center)),
    ))?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// History.

const HISTORY_W: u32 = 960;
const HISTORY_PANEL_H: u32 = 320;

/// Pixel size (width, height) of the picture [`plot_history`] makes with `panels` panels.
pub fn history_image_size(panels: usize) -> (u32, u32) {
    (HISTORY_W, HISTORY_PANEL_H * panels.max(1) as u32)
}

/// One history series: (name, one value per time).
pub type Series<'a> = (&'a str, Vec<f64>);
/// One history panel: (y-axis label, its series).
pub type HistoryPanel<'a> = (&'a str, Vec<Series<'a>>);

/// Line plot of history columns vs time: `time` in s, shown in μs; one panel per entry of
/// `panels`, stacked, each (y label, series) with series (name, values per time). Non-finite
/// values break the line. E.g. kinetic, internal, contact and total energy in one panel and the
/// contact force in a second.
pub fn plot_history(path: &Path, time: &[f64], panels: &[HistoryPanel<'_>]) -> Result<()> {
    let t_us: Vec<f64> = time.iter().map(|t| t * 1e6).collect();
    plot_lines(path, "time (μs)", &t_us, panels, false)
}

/// Line plot of series against `x` (labelled `x_desc`), as [`plot_history`]; with `markers`
/// each point is also drawn as a dot (a sweep's few runs).
pub fn plot_lines(
    path: &Path,
    x_desc: &str,
    x: &[f64],
    panels: &[HistoryPanel<'_>],
    markers: bool,
) -> Result<()> {
    if x.is_empty() || panels.is_empty() {
        return Err(Error::Invalid(format!(
            "{}: nothing to plot ({} points, {} panels)",
            path.display(),
            x.len(),
            panels.len()
        )));
    }
    register_fonts()?;
    check_writable(path)?;
    let err = draw_err(path);

    let t_us = x;
    let finite_t = t_us.iter().copied().filter(|t| t.is_finite());
    let t0 = finite_t.clone().fold(f64::MAX, f64::min);
    let t1 = finite_t.fold(f64::MIN, f64::max);
    let (t0, t1) = if t0 > t1 {
        (0.0, 1.0)
    } else if t1 - t0 <= 0.0 {
        (t0 - 0.5, t1 + 0.5)
    } else {
        let pad = if markers { 0.04 * (t1 - t0) } else { 0.0 };
        (t0 - pad, t1 + pad)
    };
    let (_, tstep) = ticks(t0, t1, 10);

    let (width, height) = history_image_size(panels.len());
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let areas = root.split_evenly((panels.len(), 1));
    for ((y_label, series), area) in panels.iter().zip(&areas) {
        let (mut lo, mut hi) = (f64::MAX, f64::MIN);
        for (_, values) in series {
            for (&v, t) in values.iter().zip(t_us) {
                if v.is_finite() && t.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
        if lo > hi {
            (lo, hi) = (0.0, 1.0);
        }
        let pad = if hi > lo {
            0.06 * (hi - lo)
        } else if lo != 0.0 {
            0.1 * lo.abs()
        } else {
            1.0
        };
        let (lo, mut hi) = (lo - pad, hi + pad);
        // Legend in the corner where it hides the fewest points; if every corner hides some,
        // make room for it above the data.
        let plot_px = (HISTORY_W - 14 - 28 - 96, HISTORY_PANEL_H - 28 - 48);
        let (mut corner, hidden, bh) = legend_corner(t_us, series, (t0, t1), (lo, hi), plot_px);
        if hidden > 0 {
            hi = lo + (hi - lo) / (1.0 - bh - 0.02);
            corner = SeriesLabelPosition::UpperRight;
        }
        let (_, ystep) = ticks(lo, hi, 6);

        let mut chart = ChartBuilder::on(area)
            .margin(14)
            .margin_right(28)
            .x_label_area_size(48)
            .y_label_area_size(96)
            .build_cartesian_2d(t0..t1, lo..hi)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .x_labels(10)
            .y_labels(6)
            .x_desc(x_desc)
            .y_desc(*y_label)
            .x_label_formatter(&|v| fmt_tick(*v, tstep))
            .y_label_formatter(&|v| fmt_tick(*v, ystep))
            .label_style(text_style(14.0))
            .axis_desc_style(text_style(16.0))
            .axis_style(AXIS_COLOR)
            .bold_line_style(RGBColor(228, 228, 228))
            .light_line_style(TRANSPARENT)
            .draw()
            .map_err(&err)?;

        for (k, (name, values)) in series.iter().enumerate() {
            let color = palette(k);
            let style = color.stroke_width(2);
            // Split at non-finite values.
            let mut segments: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for (&t, &v) in t_us.iter().zip(values) {
                if t.is_finite() && v.is_finite() {
                    if let Some(seg) = segments.last_mut() {
                        seg.push((t, v));
                    }
                } else if segments.last().is_some_and(|s| !s.is_empty()) {
                    segments.push(Vec::new());
                }
            }
            let mut labelled = false;
            if markers {
                let dots = segments
                    .iter()
                    .flatten()
                    .map(|&p| Circle::new(p, 4, color.filled()));
                chart.draw_series(dots).map_err(&err)?;
            }
            for seg in segments.into_iter().filter(|s| !s.is_empty()) {
                let anno = chart
                    .draw_series(LineSeries::new(seg, style))
                    .map_err(&err)?;
                if !labelled {
                    anno.label(*name).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
                    });
                    labelled = true;
                }
            }
        }
        chart
            .configure_series_labels()
            .position(corner)
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .label_font(text_style(14.0))
            .draw()
            .map_err(&err)?;
    }
    root.present().map_err(&err)?;
    Ok(())
}

/// The corner of the plot where a legend of these series hides the fewest data points: the
/// corner, the number of points hidden there and the legend height as a fraction of the plot.
fn legend_corner(
    t: &[f64],
    series: &[Series<'_>],
    (t0, t1): (f64, f64),
    (lo, hi): (f64, f64),
    (w, h): (u32, u32),
) -> (SeriesLabelPosition, usize, f64) {
    let longest = series
        .iter()
        .map(|(n, _)| n.chars().count())
        .max()
        .unwrap_or(0);
    // Legend box as a fraction of the plot area (8 px per character, 20 px per row).
    let bw = ((50 + 8 * longest) as f64 / w.max(1) as f64).min(1.0);
    let bh = ((12 + 20 * series.len()) as f64 / h.max(1) as f64).min(1.0);
    let corners = [
        (SeriesLabelPosition::UpperRight, 1.0 - bw, 1.0 - bh),
        (SeriesLabelPosition::UpperLeft, 0.0, 1.0 - bh),
        (SeriesLabelPosition::LowerRight, 1.0 - bw, 0.0),
        (SeriesLabelPosition::LowerLeft, 0.0, 0.0),
    ];
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, u0, v0) in corners {
        let mut hidden = 0;
        for (_, values) in series {
            for (&ti, &v) in t.iter().zip(values) {
                let u = (ti - t0) / (t1 - t0);
                let w = (v - lo) / (hi - lo);
                if u >= u0 - 0.02 && u <= u0 + bw + 0.02 && w >= v0 - 0.04 && w <= v0 + bh + 0.04 {
                    hidden += 1;
                }
            }
        }
        if hidden < best.0 {
            best = (hidden, pos);
        }
    }
    (best.1, best.0, bh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::Vector;

    #[test]
    fn section_3d_selects_slab_and_axes() {
        let mut p = Particles::<3>::default();
        for k in 0..5 {
            let x = Vector::<3>::new(k as f64, 0.1 * k as f64, 2.0 * k as f64);
            p.push(
                x,
                Vector::<3>::new(3.0, 4.0, 0.0),
                1.0,
                1000.0,
                1.0,
                k as u32,
            );
        }
        p.push_copy(2);
        p.n_real = 5;
        let spec = PictureSpec {
            times: vec![0.0],
            normal_axis: 1,
            position: 0.2,
            thickness: None,
            color_by: ColorBy::Velocity,
        };
        let f = extract_section(&p, 1e-6, &spec, 0.25);
        assert_eq!(f.points, vec![[1.0, 2.0], [2.0, 4.0], [3.0, 6.0]]);
        assert_eq!(f.values, vec![5.0; 3]);
        assert_eq!(f.bodies, vec![1, 2, 3]);
        assert_eq!(f.time, 1e-6);
    }

    #[test]
    fn section_2d_takes_all_real() {
        let mut p = Particles::<2>::default();
        for k in 0..4 {
            p.push(
                Vector::<2>::new(k as f64, 1.0),
                Vector::<2>::zeros(),
                1.0,
                1.0,
                1.0,
                0,
            );
            p.p[k] = k as f64;
        }
        p.push_copy(0);
        p.n_real = 4;
        let spec = PictureSpec {
            times: vec![],
            normal_axis: 2,
            position: 100.0,
            thickness: None,
            color_by: ColorBy::Pressure,
        };
        let f = extract_section(&p, 0.0, &spec, 1e-9);
        assert_eq!(f.points.len(), 4);
        assert_eq!(f.values, vec![0.0, 1.0, 2.0, 3.0]);
    }

    #[test]
    fn spacing_of_a_grid() {
        let pts: Vec<[f64; 2]> = (0..50 * 30)
            .map(|k| [(k % 50) as f64 * 0.5e-3, (k / 50) as f64 * 0.5e-3])
            .collect();
        let s = typical_spacing(&pts).unwrap();
        assert!((s - 0.5e-3).abs() < 1e-12, "{s}");
        // A sparse frame: two small blocks far apart.
        let mut pts2: Vec<[f64; 2]> = (0..100)
            .map(|k| [(k % 10) as f64 * 1e-3, (k / 10) as f64 * 1e-3])
            .collect();
        pts2.extend((0..100).map(|k| [1.0 + (k % 10) as f64 * 1e-3, 1.0 + (k / 10) as f64 * 1e-3]));
        let s = typical_spacing(&pts2).unwrap();
        assert!((s - 1e-3).abs() < 1e-12, "{s}");
    }

    #[test]
    fn viridis_ends_and_ticks() {
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(f64::NAN), RGBColor(68, 1, 84));
        assert_eq!(nice_step(10.0, 5), 2.0);
        assert_eq!(fmt_tick(2.5, 0.5), "2.5");
        assert_eq!(fmt_tick(-0.25, 0.25), "-0.25");
        assert_eq!(fmt_tick(20.0, 10.0), "20");
        let (t, _) = ticks(-1.0, 1.0, 4);
        assert_eq!(t, vec![-1.0, -0.5, 0.0, 0.5, 1.0]);
    }
}
