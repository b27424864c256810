//! The paper's figures for a sweep, as SVG and PNG (plotters):
//!
//! - `solution`: every unknown over time (paper Fig. 2/3, 8/9),
//! - `error`: the pointwise error over time, log scale (Fig. 4/10),
//! - `residuals`: constraint residuals per level and the energy drift, log
//!   scale (Fig. 5/11),
//!
//! these three at the figure tolerance with one curve per pair, and
//! - `work_precision`: `err` against `tsim`, log-log, one line per
//!   solver(formulation) through its tolerances, with the Pareto front
//!   (Fig. 6/12). On the paper's scenarios S01/S02 it also carries the
//!   Fortran codes' curves on the swept formulations as reference lines
//!   ([`super::fortran`], [`reference_look`]). Without a reference it plots
//!   the position-constraint residual instead of the error.
//!
//! A figure is first described as data ([`Figure`]: panels of series) and
//! then drawn by one renderer on either backend. **One colour per solver,
//! one marker per formulation** ([`look`]), the same in every figure and
//! every sweep, so the legend is compact — the solvers by colour, the
//! formulations by marker ([`compact_legend`]) — instead of one entry per
//! pair (58 at 40 pairs). Curves over time carry a few markers spaced along
//! them ([`Markers::Sparse`]) so that their formulation can be read too. At
//! more than [`FEW_CURVES`] pairs the solution figure shows one curve per
//! solver (its most accurate formulation) and the error figure one panel
//! per solver. A Fortran reference line is dotted, in a grey tinted per
//! code, with hollow markers of its formulation's shape. Axes carry no
//! units: the model language declares none, and a unit guessed from a name
//! is wrong for the next model (`tsim` is measured, in seconds).

use super::fortran::ReferenceLines;
use super::table::tol_label;
use super::{write, SweepReport, SweepRun};
use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Width of the legend strip on the right of every figure, in pixels.
const LEGEND_WIDTH: u32 = 250;
/// Height of the title band, in pixels.
const TITLE_HEIGHT: u32 = 44;
/// The lowest value a log axis shows; smaller values and exact zeros are
/// drawn there (plotters labels no tick below `f64::EPSILON`).
const LOG_FLOOR: f64 = 1e-16;

/// Why a figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The plotting library failed (e.g. no usable font).
    #[error("drawing failed: {0}")]
    Draw(String),
    /// The file could not be written.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The embedded font could not be registered with the plotting library.
    #[error("the embedded font {file} could not be registered as `{family}`")]
    Font {
        /// The family name the figures use.
        family: &'static str,
        /// The font file, relative to the repository.
        file: &'static str,
    },
}

fn draw_err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// Point markers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// No marker.
    None,
    /// A circle.
    Circle,
    /// A triangle.
    Triangle,
    /// A square.
    Square,
    /// A diamond.
    Diamond,
    /// A triangle pointing down.
    TriangleDown,
    /// A diagonal cross.
    Cross,
    /// An upright cross.
    Plus,
    /// A hexagon.
    Hexagon,
    /// A five-pointed star.
    Star,
}

/// How a line is stroked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Line {
    /// Continuous.
    Solid,
    /// Dashes of 9 px, gaps of 5 px.
    Dashed,
    /// Short dashes of 3 px, gaps of 4 px (the Fortran reference lines).
    Dotted,
    /// No line: markers only (the formulations' legend entries).
    Hidden,
}

/// How a series looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    /// Colour.
    pub color: RGBColor,
    /// Stroke of the line.
    pub line: Line,
    /// Marker at the data points (drawn only where `markers` is asked).
    pub marker: Marker,
    /// Markers are outlines on white instead of filled.
    pub hollow: bool,
    /// Colour of the markers (usually `color`).
    pub marker_color: RGBColor,
    /// Line width in pixels.
    pub width: u32,
}

/// Colours of the solvers (in [`dae_solvers::SOLVER_NAMES`] order): a
/// categorical palette (Tableau 10) with grey left for the Fortran
/// reference lines.
pub const SOLVER_COLORS: [RGBColor; 7] = [
    RGBColor(31, 119, 180),  // radau5 blue
    RGBColor(255, 127, 14),  // bdf orange
    RGBColor(44, 160, 44),   // odradau green
    RGBColor(214, 39, 40),   // odbdf red
    RGBColor(148, 103, 189), // mebdf purple
    RGBColor(140, 86, 75),   // idec brown
    RGBColor(227, 119, 194), // gauss pink
];

/// Colour of a solver this table does not know.
const OTHER_COLOR: RGBColor = RGBColor(90, 90, 90);

/// Markers of the formulations (in
/// [`dae_core::system::FORMULATION_NAMES`] order).
pub const FORMULATION_MARKERS: [Marker; 9] = [
    Marker::Circle,       // ori2
    Marker::Triangle,     // rcd1
    Marker::Square,       // rcd0
    Marker::Diamond,      // ovd1
    Marker::TriangleDown, // ovd0
    Marker::Cross,        // ggl1
    Marker::Plus,         // psi1
    Marker::Hexagon,      // psi0
    Marker::Star,         // mex0
];

/// At most this many pairs, the solution and error figures draw every
/// pair at the figure tolerance; beyond, one curve (solution) or one panel
/// (error) per solver.
pub const FEW_CURVES: usize = 8;

/// The colour of a solver.
///
/// ```
/// use dae::sweep::plot::{solver_color, SOLVER_COLORS};
///
/// assert_eq!(solver_color("odradau"), SOLVER_COLORS[2]);
/// assert_ne!(solver_color("radau5"), solver_color("mebdf"));
/// ```
pub fn solver_color(solver: &str) -> RGBColor {
    dae_solvers::SOLVER_NAMES
        .iter()
        .position(|n| *n == solver)
        .and_then(|i| SOLVER_COLORS.get(i).copied())
        .unwrap_or(OTHER_COLOR)
}

/// The marker of a formulation.
///
/// ```
/// use dae::sweep::plot::{formulation_marker, Marker};
///
/// assert_eq!(formulation_marker("rcd0"), Marker::Square);
/// ```
pub fn formulation_marker(formulation: &str) -> Marker {
    dae_core::system::FORMULATION_NAMES
        .iter()
        .position(|n| *n == formulation)
        .and_then(|i| FORMULATION_MARKERS.get(i).copied())
        .unwrap_or(Marker::Circle)
}

/// The look of a pair: the solver's colour and the formulation's marker,
/// a solid line.
///
/// ```
/// use dae::sweep::plot::look;
///
/// // radau5, odradau and mebdf on rcd0: three colours, one marker.
/// let [a, b, c] = ["radau5", "odradau", "mebdf"].map(|s| look(s, "rcd0"));
/// assert!(a.color != b.color && b.color != c.color && a.color != c.color);
/// assert!(a.marker == b.marker && b.marker == c.marker);
/// ```
pub fn look(solver: &str, formulation: &str) -> Look {
    let color = solver_color(solver);
    Look {
        color,
        line: Line::Solid,
        marker: formulation_marker(formulation),
        hollow: false,
        marker_color: color,
        width: 2,
    }
}

/// The look of a Fortran reference line ([`super::fortran`]): dotted, in a
/// grey tinted per code (so never one of our solvers' saturated colours),
/// with hollow markers of the formulation's shape outlined in dark grey.
pub fn reference_look(code: &str, formulation: &str) -> Look {
    let tint = match code.split('-').next().unwrap_or(code) {
        "radau5" => RGBColor(31, 119, 180),
        "dassl" => RGBColor(255, 127, 14),
        "daspk" => RGBColor(188, 189, 34),
        "odassl" => RGBColor(214, 39, 40),
        "mebdf" if code.contains('-') => RGBColor(23, 190, 207),
        "mebdf" => RGBColor(148, 103, 189),
        _ => RGBColor(128, 128, 128),
    };
    let RGBColor(r, g, b) = tint;
    let grey = |c: u8| (0.35 * f64::from(c) + 0.65 * 128.0).round() as u8;
    let color = RGBColor(grey(r), grey(g), grey(b));
    Look {
        color,
        line: Line::Dotted,
        marker: formulation_marker(formulation),
        hollow: true,
        marker_color: color,
        width: 2,
    }
}

/// The compact legend of a figure: a heading and one entry per solver (its
/// colour, a line), a heading and one entry per formulation (its marker in
/// dark grey, no line), each in the order given.
///
/// ```
/// use dae::sweep::plot::compact_legend;
///
/// let s = ["radau5", "bdf"].map(String::from);
/// let f = ["rcd0", "ggl1", "psi0"].map(String::from);
/// // 2 headings + 2 solvers + 3 formulations, not 6 pairs.
/// assert_eq!(compact_legend(&s, &f, true).len(), 7);
/// ```
pub fn compact_legend(
    solvers: &[String],
    formulations: &[String],
    with_markers: bool,
) -> Vec<(String, Look, bool)> {
    let heading = |text: &str| {
        (
            text.to_string(),
            Look {
                line: Line::Hidden,
                marker: Marker::None,
                ..look("", "")
            },
            false,
        )
    };
    let mut out = vec![heading("solver (colour)")];
    out.extend(solvers.iter().map(|s| {
        (
            s.clone(),
            Look {
                marker: Marker::None,
                width: 3,
                ..look(s, "")
            },
            false,
        )
    }));
    if with_markers {
        out.push(heading("formulation (marker)"));
        out.extend(formulations.iter().map(|f| {
            let grey = RGBColor(60, 60, 60);
            (
                f.clone(),
                Look {
                    color: grey,
                    marker_color: grey,
                    line: Line::Hidden,
                    ..look("", f)
                },
                true,
            )
        }));
    }
    out
}

/// Where a panel draws its curves' markers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Markers {
    /// None.
    None,
    /// At every data point (a work-precision line through its tolerances).
    Every,
    /// About a dozen along each curve, shifted from curve to curve so that
    /// coinciding curves show each marker (curves over time).
    Sparse,
}

/// One curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend label, `solver(formulation)`.
    pub label: String,
    /// Look.
    pub look: Look,
    /// Data points.
    pub points: Vec<(f64, f64)>,
    /// Text drawn beside some points: `(index into points, text)` (the
    /// tolerances at the ends of a work-precision line).
    pub labels: Vec<(usize, String)>,
}

/// One chart of a figure.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Caption above the chart.
    pub title: String,
    /// x-axis description with unit.
    pub x_label: String,
    /// y-axis description with unit.
    pub y_label: String,
    /// Logarithmic x axis.
    pub x_log: bool,
    /// Logarithmic y axis.
    pub y_log: bool,
    /// Where markers are drawn.
    pub markers: Markers,
    /// On a log axis, leave out exact zeros (an error or drift at `t0`)
    /// instead of drawing them on the lower edge.
    pub drop_zeros: bool,
    /// Curves.
    pub series: Vec<Series>,
}

/// A figure: a title, a grid of panels and one legend.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// File stem (`solution` → `solution.svg`, `solution.png`).
    pub file: String,
    /// Title.
    pub title: String,
    /// What the figure shows (for `index.html`).
    pub caption: String,
    /// Panels, row-major.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub cols: usize,
    /// Size in pixels.
    pub size: (u32, u32),
    /// Legend entries (label, look, with marker).
    pub legend: Vec<(String, Look, bool)>,
}

/// The figures of a sweep and notes on the ones left out.
#[derive(Clone, Debug, Default)]
pub struct Figures {
    /// Figures to draw.
    pub figures: Vec<Figure>,
    /// Why a figure is missing or what it shows instead.
    pub notes: Vec<String>,
}

fn level_name(level: u8) -> &'static str {
    match level {
        0 => "position",
        1 => "velocity",
        2 => "acceleration",
        _ => "higher",
    }
}

fn label(run: &SweepRun) -> String {
    format!("{}({})", run.record.solver, run.record.formulation)
}

/// The solvers and formulations of some runs, each in order of first
/// appearance.
fn solvers_and_formulations<'a>(
    runs: impl Iterator<Item = (&'a str, &'a str)>,
) -> (Vec<String>, Vec<String>) {
    let (mut solvers, mut formulations): (Vec<String>, Vec<String>) = (Vec::new(), Vec::new());
    for (s, f) in runs {
        if !solvers.iter().any(|x| x == s) {
            solvers.push(s.to_string());
        }
        if !formulations.iter().any(|x| x == f) {
            formulations.push(f.to_string());
        }
    }
    (solvers, formulations)
}

fn legend_of(runs: &[&SweepRun]) -> Vec<(String, Look, bool)> {
    let (solvers, formulations) = solvers_and_formulations(
        runs.iter()
            .map(|r| (r.record.solver.as_str(), r.record.formulation.as_str())),
    );
    compact_legend(&solvers, &formulations, true)
}

/// The most accurate run of each solver (by `err`, else the
/// position-constraint residual), solvers in run order.
fn best_per_solver<'a>(report: &SweepReport, runs: &[&'a SweepRun]) -> Vec<&'a SweepRun> {
    let (solvers, _) = solvers_and_formulations(
        runs.iter()
            .map(|r| (r.record.solver.as_str(), r.record.formulation.as_str())),
    );
    solvers
        .iter()
        .filter_map(|s| {
            runs.iter()
                .copied()
                .filter(|r| &r.record.solver == s)
                .min_by(|a, b| score(report, a).total_cmp(&score(report, b)))
        })
        .collect()
}

/// What "most accurate" sorts by: `err`, or without a reference the
/// position-constraint residual; a missing value last.
fn score(report: &SweepReport, r: &SweepRun) -> f64 {
    if report.has_reference() {
        r.record.err
    } else {
        r.record.residuals.level(0)
    }
    .filter(|v| v.is_finite())
    .unwrap_or(f64::INFINITY)
}

fn grid_size(panels: usize, cols: usize, panel_h: u32, width: u32) -> (u32, u32) {
    let rows = panels.div_ceil(cols.max(1)).max(1) as u32;
    (width, TITLE_HEIGHT + rows * panel_h)
}

/// Describe the figures of a sweep.
pub fn figures(report: &SweepReport) -> Figures {
    let mut out = Figures::default();
    let runs = report.figure_runs();
    let tol = tol_label(report.figure_tol);
    let name = &report.scene.name;
    let sampled_at = if report.scene.checks >= super::CHECKS_AS_SAMPLES {
        " (plotted at the check times only)"
    } else {
        ""
    };
    if runs.is_empty() {
        out.notes.push(format!(
            "no run succeeded at the figure tolerance {tol}: the solution, error and residual figures are left out"
        ));
    } else {
        out.figures
            .push(solution_figure(report, &runs, &tol, sampled_at));
        if report.has_reference() {
            out.figures
                .push(error_figure(report, &runs, &tol, sampled_at));
        } else {
            out.notes.push(format!(
                "scene {name} has no reference ([reference] kind = \"none\"): no error figure; the work-precision \
                 diagram plots the position-constraint residual instead of the error"
            ));
        }
        out.figures.push(residual_figure(
            report,
            &per_formulation(report, &runs),
            &tol,
            sampled_at,
        ));
    }
    let lines = match ReferenceLines::for_report(report) {
        Ok(lines) => lines,
        Err(e) => {
            out.notes.push(format!(
                "the Fortran reference lines of the work-precision diagram are left out: {e}"
            ));
            None
        }
    };
    match work_precision_figure(report, lines.as_ref()) {
        Some(f) => out.figures.push(f),
        None => out.notes.push(
            "no successful run with a finite error: the work-precision diagram is left out".into(),
        ),
    }
    if let Some(f) = scd_figure(report) {
        out.figures.push(f);
    }
    out
}

fn solution_figure(report: &SweepReport, all: &[&SweepRun], tol: &str, sampled_at: &str) -> Figure {
    let few = all.len() <= FEW_CURVES;
    let best;
    let runs: &[&SweepRun] = if few {
        all
    } else {
        best = best_per_solver(report, all);
        &best
    };
    let panels: Vec<Panel> = report
        .variables
        .iter()
        .map(|v| Panel {
            title: v.clone(),
            x_label: "t".into(),
            y_label: v.to_string(),
            x_log: false,
            y_log: false,
            markers: Markers::Sparse,
            drop_zeros: false,
            series: runs
                .iter()
                .filter_map(|r| {
                    let tr = &r.record.trajectory;
                    let i = tr.names.iter().position(|n| n == v)?;
                    Some(Series {
                        label: label(r),
                        look: look(&r.record.solver, &r.record.formulation),
                        labels: Vec::new(),
                        points: tr.t.iter().zip(&tr.y).map(|(t, y)| (*t, y[i])).collect(),
                    })
                })
                .collect(),
        })
        .collect();
    let cols = if panels.len() > 1 { 2 } else { 1 };
    Figure {
        file: "solution".into(),
        title: format!(
            "{}: numerical solution{}, RTOL = ATOL = {tol}",
            report.scene.name,
            if sampled_at.is_empty() {
                ""
            } else {
                " at the check times"
            }
        ),
        caption: if few {
            format!(
                "Every unknown over time at RTOL = ATOL = {tol}, one curve per solver(formulation){sampled_at} \
                 (paper Fig. 3 / 9); colour: solver, marker: formulation."
            )
        } else {
            format!(
                "Every unknown over time at RTOL = ATOL = {tol}{sampled_at} (paper Fig. 3 / 9): one curve per \
                 solver, its most accurate formulation at this tolerance (colour: solver, marker: formulation), \
                 so that {} pairs do not hide each other; the error figure below shows every pair, one panel \
                 per solver, and results.csv every run.",
                all.len()
            )
        },
        size: grid_size(panels.len(), cols, 300, 1400),
        panels,
        cols,
        legend: legend_of(runs),
    }
}

fn error_figure(report: &SweepReport, runs: &[&SweepRun], tol: &str, sampled_at: &str) -> Figure {
    let series_of = |rs: &[&SweepRun]| -> Vec<Series> {
        rs.iter()
            .map(|r| Series {
                label: label(r),
                look: look(&r.record.solver, &r.record.formulation),
                labels: Vec::new(),
                points: r.record.trajectory.err.clone(),
            })
            .collect()
    };
    let what = "max(|x−x*|, |y−y*|, |v−v*|, |w−w*|)";
    let panel = |title: String, series: Vec<Series>| Panel {
        title,
        x_label: "t".into(),
        y_label: "error".into(),
        x_log: false,
        y_log: true,
        markers: Markers::Sparse,
        drop_zeros: true,
        series,
    };
    let few = runs.len() <= FEW_CURVES;
    let panels: Vec<Panel> = if few {
        vec![panel(what.into(), series_of(runs))]
    } else {
        let (solvers, _) = solvers_and_formulations(
            runs.iter()
                .map(|r| (r.record.solver.as_str(), r.record.formulation.as_str())),
        );
        solvers
            .iter()
            .map(|s| {
                let mine: Vec<&SweepRun> = runs
                    .iter()
                    .copied()
                    .filter(|r| &r.record.solver == s)
                    .collect();
                // One colour per panel: hollow markers stand out on the
                // lines and tell the formulations apart.
                let mut series = series_of(&mine);
                for x in &mut series {
                    x.look.hollow = true;
                }
                panel(s.clone(), series)
            })
            .collect()
    };
    let cols = if panels.len() > 1 { 2 } else { 1 };
    Figure {
        file: "error".into(),
        title: format!(
            "{}: error against the exact solution{}, RTOL = ATOL = {tol}",
            report.scene.name,
            if sampled_at.is_empty() { "" } else { " at the check times" }
        ),
        caption: format!(
            "Largest pointwise error of the differential unknowns, {what}, over time at RTOL = ATOL = \
             {tol}{sampled_at}; log scale (paper Fig. 4 / 10){}; colour: solver, marker: formulation. Exact \
             zeros (t = t0) are left out; values below 1e-16 are drawn on the lower edge.",
            if few {
                ""
            } else {
                ", one panel per solver with one curve per formulation (panels share no axis range)"
            }
        ),
        size: if few {
            (1300, 700)
        } else {
            grid_size(panels.len(), cols, 340, 1400)
        },
        panels,
        cols,
        legend: legend_of(runs),
    }
}

fn per_formulation<'a>(report: &SweepReport, runs: &[&'a SweepRun]) -> Vec<&'a SweepRun> {
    let score = |r: &SweepRun| score(report, r);
    report
        .formulations
        .iter()
        .filter_map(|f| {
            runs.iter()
                .copied()
                .filter(|r| &r.record.formulation == f)
                .min_by(|a, b| score(a).total_cmp(&score(b)))
        })
        .collect()
}

fn residual_figure(
    report: &SweepReport,
    runs: &[&SweepRun],
    tol: &str,
    sampled_at: &str,
) -> Figure {
    let mut levels: Vec<u8> = report
        .constraints
        .iter()
        .map(|(l, _)| *l)
        .filter(|l| *l < 3)
        .collect();
    levels.dedup();
    let mut panels: Vec<Panel> = levels
        .iter()
        .map(|&l| {
            let exprs: Vec<&str> = report
                .constraints
                .iter()
                .filter(|(k, _)| *k == l)
                .map(|(_, e)| e.as_str())
                .collect();
            let title = if exprs.len() == 1 && exprs[0].chars().count() <= 40 {
                format!("{} level: 0 = {}", level_name(l), exprs[0])
            } else {
                if exprs.len() == 1 {
                    format!("{} level", level_name(l))
                } else {
                    format!(
                        "{} level: largest |g| of {} constraints",
                        level_name(l),
                        exprs.len()
                    )
                }
            };
            Panel {
                title,
                x_label: "t".into(),
                y_label: format!("|g{}|", subscript(l)),
                x_log: false,
                y_log: true,
                markers: Markers::Sparse,
                drop_zeros: false,
                series: runs
                    .iter()
                    .map(|r| {
                        let tr = &r.record.trajectory;
                        Series {
                            label: label(r),
                            look: look(&r.record.solver, &r.record.formulation),
                            labels: Vec::new(),
                            points: tr
                                .t
                                .iter()
                                .zip(&tr.residuals)
                                .filter_map(|(t, g)| g.get(l as usize).map(|g| (*t, *g)))
                                .collect(),
                        }
                    })
                    .collect(),
            }
        })
        .collect();
    if let Some(inv) = report.invariants.first() {
        panels.push(Panel {
            title: format!("drift of the invariant `{inv}`"),
            x_label: "t".into(),
            y_label: format!("|{inv}(t) − {inv}(t0)|"),
            x_log: false,
            y_log: true,
            markers: Markers::Sparse,
            drop_zeros: true,
            series: runs
                .iter()
                .map(|r| {
                    let tr = &r.record.trajectory;
                    Series {
                        label: label(r),
                        look: look(&r.record.solver, &r.record.formulation),
                        labels: Vec::new(),
                        points: tr.t.iter().zip(&tr.drift).map(|(t, d)| (*t, *d)).collect(),
                    }
                })
                .collect(),
        });
    }
    let cols = if panels.len() > 1 { 2 } else { 1 };
    Figure {
        file: "residuals".into(),
        title: format!("{}: constraint residuals and drift, RTOL = ATOL = {tol}", report.scene.name),
        caption: format!(
            "Absolute residuals of the constraints per level, hidden ones included (largest over the constraints of \
             a level), and the drift of the {} at RTOL = ATOL = {tol}{sampled_at}; log scale (paper Fig. 5 / 11). \
             One curve per formulation: its most accurate solver at this tolerance (named in the legend). \
             Residuals are in the units of the constraints as written. Values below 1e-16, exact zeros \
             included, are drawn on the lower edge.",
            report.invariants.first().map_or("first invariant", String::as_str)
        ),
        size: grid_size(panels.len(), cols, 380, 1400),
        panels,
        cols,
        legend: legend_of(runs),
    }
}

fn subscript(level: u8) -> &'static str {
    ["₀", "₁", "₂"].get(level as usize).copied().unwrap_or("")
}

/// One series per applicable pair through its successful runs, loose to
/// tight tolerance, with the points `point` gives (finite ones only).
fn pair_series(
    report: &SweepReport,
    point: impl Fn(&SweepRun) -> Option<(f64, f64)>,
) -> (Vec<Series>, Vec<(String, Look, bool)>) {
    let mut series = Vec::new();
    let mut drawn: Vec<(&str, &str)> = Vec::new();
    for p in report.pairs.iter().filter(|p| p.not_applicable.is_none()) {
        let mut runs: Vec<&SweepRun> = report
            .runs
            .iter()
            .filter(|r| {
                r.record.solver == p.solver
                    && r.record.formulation == p.formulation
                    && r.record.status == "ok"
            })
            .collect();
        runs.sort_by(|a, b| b.record.tol.total_cmp(&a.record.tol));
        let (pts, tols): (Vec<(f64, f64)>, Vec<f64>) = runs
            .iter()
            .filter_map(|r| point(r).map(|q| (q, r.record.tol)))
            .filter(|((x, y), _)| x.is_finite() && y.is_finite())
            .unzip();
        if pts.is_empty() {
            continue;
        }
        // The tolerances at the two ends of the line.
        let mut labels = vec![(0, tol_label(tols[0]))];
        if pts.len() > 1 {
            labels.push((pts.len() - 1, tol_label(tols[pts.len() - 1])));
        }
        let l = format!("{}({})", p.solver, p.formulation);
        let lk = look(&p.solver, &p.formulation);
        drawn.push((p.solver.as_str(), p.formulation.as_str()));
        series.push(Series {
            label: l,
            look: lk,
            labels,
            points: pts,
        });
    }
    let (solvers, formulations) = solvers_and_formulations(drawn.into_iter());
    (series, compact_legend(&solvers, &formulations, true))
}

/// The IVP Test Set's work-precision diagram: the integration time against
/// the significant correct digits, for a reference with its own values.
fn scd_figure(report: &SweepReport) -> Option<Figure> {
    let (series, legend) = pair_series(report, |r| {
        r.record
            .scd
            .map(|scd| (scd, r.record.tsim_s))
            .filter(|(_, t)| *t > 0.0)
    });
    if series.is_empty() {
        return None;
    }
    Some(Figure {
        file: "scd".into(),
        title: format!("{}: significant correct digits", report.scene.name),
        caption: format!(
            "The integration time tsim (minimum of at least {} timed runs, log scale) against the significant correct \
             digits scd = −log10 of the largest scaled error of the unknowns the reference gives, over its \
             times — the IVP Test Set's work-precision diagram; one line per solver(formulation) through its \
             successful tolerances. Further right is more accurate, lower is cheaper.",
            report.repeats
        ),
        panels: vec![Panel {
            title: "integration time against significant correct digits".into(),
            x_label: "scd".into(),
            y_label: "tsim [s]".into(),
            x_log: false,
            y_log: true,
            markers: Markers::Every,
            drop_zeros: true,
            series,
        }],
        cols: 1,
        size: (1300, 850),
        legend,
    })
}

/// The work-precision diagram; `lines`, the Fortran codes' curves of the
/// scenario, are drawn under our lines (and above the Pareto band).
fn work_precision_figure(report: &SweepReport, lines: Option<&ReferenceLines>) -> Option<Figure> {
    let with_ref = report.has_reference();
    let (ours, mut legend) = pair_series(report, |r| {
        let y = if with_ref {
            r.record.err
        } else {
            r.record.residuals.level(0)
        };
        y.map(|y| (r.record.tsim_s, y)).filter(|(t, _)| *t > 0.0)
    });
    if ours.is_empty() {
        return None;
    }
    // Drawn first to last: the Pareto band, the Fortran lines, ours.
    let mut series = Vec::new();
    if with_ref {
        let front = super::pareto::pareto_front(&report.runs);
        if front.len() > 1 {
            // A wide grey band under the pairs' lines.
            let lk = Look {
                color: RGBColor(200, 200, 200),
                line: Line::Solid,
                marker: Marker::None,
                hollow: false,
                marker_color: RGBColor(200, 200, 200),
                width: 9,
            };
            legend.push(("Pareto front".into(), lk, false));
            series.push(Series {
                label: "Pareto front".into(),
                look: lk,
                labels: Vec::new(),
                points: front.iter().map(|p| (p.tsim_s, p.err)).collect(),
            });
        }
    }
    // Without a reference the y axis is a residual: no Fortran lines.
    let lines = lines.filter(|_| with_ref);
    for c in lines.iter().flat_map(|l| &l.curves) {
        let lk = reference_look(&c.code, &c.formulation);
        // One legend entry per code (its grey, dotted); the formulation is
        // the marker, as for ours.
        let code_label = c.label.replace(&format!(", {}", c.formulation), "");
        if !legend.iter().any(|(l, _, _)| *l == code_label) {
            let entry = Look {
                marker: Marker::None,
                ..lk
            };
            legend.push((code_label, entry, false));
        }
        series.push(Series {
            label: c.label.clone(),
            look: lk,
            labels: Vec::new(),
            points: c.points.iter().map(|p| (p.time_s, p.err)).collect(),
        });
    }
    series.extend(ours);
    let tols: Vec<String> = report.tolerances.iter().map(|t| tol_label(*t)).collect();
    let (title, y_label, what) = if with_ref {
        (
            format!(
                "{}: work-precision diagram{}",
                report.scene.name,
                if lines.is_some() {
                    ", with the Fortran codes"
                } else {
                    ""
                }
            ),
            "err".to_string(),
            "err (largest pointwise error of the differential unknowns over the check times)"
                .to_string(),
        )
    } else {
        (
            format!("{}: work vs position-constraint residual (no reference)", report.scene.name),
            "|g₀| (largest over check times)".to_string(),
            "the largest position-constraint residual over the check times (the scene has no reference, so no error)"
                .to_string(),
        )
    };
    // Tall enough for every legend entry.
    let height = (TITLE_HEIGHT + 80 + 26 * legend.len() as u32).max(850);
    Some(Figure {
        file: "work_precision".into(),
        title,
        caption: format!(
            "{what} against the integration time tsim (minimum of at least {} timed runs), log-log; one line per \
             solver(formulation) through its successful tolerances {}{} (paper Fig. 6 / 12).{}",
            report.repeats,
            tols.join(", "),
            if with_ref {
                format!(
                    "; wide grey band: the Pareto front of this sweep's runs (times within {} % tied, the more \
                     accurate run kept: the table's rule)",
                    100.0 * super::pareto::TIME_RESOLUTION
                )
            } else {
                String::new()
            },
            lines.map_or_else(String::new, |l| format!(" {}", l.note))
        ),
        panels: vec![Panel {
            title: if with_ref {
                "error against integration time".into()
            } else {
                "position-constraint residual against integration time".into()
            },
            x_label: if lines.is_some() {
                "tsim [s] (Fortran: time_median_s or cpu_s, see caption)".into()
            } else {
                "tsim [s]".into()
            },
            y_label,
            x_log: true,
            y_log: true,
            markers: Markers::Every,
            drop_zeros: true,
            series,
        }],
        cols: 1,
        size: (1300, height),
        legend,
    })
}

/// Axis range of a panel's data: linear with 4 % padding, or whole decades
/// for a log axis (values at or below zero go to the floor).
fn range(values: impl Iterator<Item = f64> + Clone, log: bool) -> (f64, f64) {
    let finite = values.filter(|v| v.is_finite());
    if log {
        let pos = finite.filter(|v| *v > 0.0);
        let lo = pos.clone().fold(f64::INFINITY, f64::min).max(LOG_FLOOR);
        let hi = pos.fold(0.0f64, f64::max);
        if !lo.is_finite() || hi <= 0.0 {
            return (LOG_FLOOR, LOG_FLOOR * 1e3);
        }
        let lo = 10f64.powf(lo.log10().floor());
        let mut hi = 10f64.powf(hi.log10().ceil());
        if hi <= lo {
            hi = lo * 10.0;
        }
        // A hair beyond the decades, so that both end decades get a tick
        // despite rounding in the tick generator.
        (lo * (1.0 - 1e-9), hi * (1.0 + 1e-9))
    } else {
        let lo = finite.clone().fold(f64::INFINITY, f64::min);
        let hi = finite.fold(f64::NEG_INFINITY, f64::max);
        if !lo.is_finite() || !hi.is_finite() {
            return (0.0, 1.0);
        }
        let span = hi - lo;
        if span <= 1e-12 * (1.0 + lo.abs().max(hi.abs())) {
            let d = 0.5 * (1.0 + lo.abs().max(hi.abs())) * 1e-3;
            return (lo - d.max(1e-12), hi + d.max(1e-12));
        }
        (lo - 0.04 * span, hi + 0.04 * span)
    }
}

/// Tick label of a log axis: `1e-7`, or `3e-7` between decades.
fn log_tick(v: f64) -> String {
    if v <= 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.log10().round();
    let (e, m) = if (v / 10f64.powf(e) - 1.0).abs() < 1e-6 {
        (e as i32, 1)
    } else {
        let e = v.log10().floor();
        (e as i32, (v / 10f64.powf(e)).round() as i64)
    };
    match e {
        // 0.01 … 100 read better in decimal.
        -1 => format!("0.{m}"),
        -2 => format!("0.0{m}"),
        0..=2 => format!("{}", m * 10i64.pow(e as u32)),
        _ => format!("{m}e{e}"),
    }
}

/// Tick label of a linear axis: short and without float noise (a value
/// tiny against the axis span is 0).
fn lin_tick(v: f64, span: f64) -> String {
    if v == 0.0 || v.abs() <= 1e-9 * span.abs() {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

/// Split a pixel polyline into dashes of `on` pixels separated by gaps of
/// `off` pixels, measured along the line.
fn dashes(px: &[(i32, i32)], on: f64, off: f64) -> Vec<Vec<(i32, i32)>> {
    let mut out: Vec<Vec<(i32, i32)>> = Vec::new();
    let mut cur: Vec<(i32, i32)> = Vec::new();
    let (mut drawing, mut left) = (true, on);
    for w in px.windows(2) {
        let (a, b) = (
            (w[0].0 as f64, w[0].1 as f64),
            (w[1].0 as f64, w[1].1 as f64),
        );
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let mut pos = 0.0;
        if drawing && cur.is_empty() {
            cur.push(w[0]);
        }
        while len - pos > left {
            pos += left;
            let f = pos / len;
            let p = (
                (a.0 + f * (b.0 - a.0)).round() as i32,
                (a.1 + f * (b.1 - a.1)).round() as i32,
            );
            if drawing {
                cur.push(p);
                out.push(std::mem::take(&mut cur));
            } else {
                cur.push(p);
            }
            drawing = !drawing;
            left = if drawing { on } else { off };
        }
        left -= len - pos;
        if drawing {
            cur.push(w[1]);
        } else {
            cur.clear();
        }
    }
    if drawing && cur.len() > 1 {
        out.push(cur);
    }
    out
}

/// Stroke a pixel polyline. `segmented` draws it segment by segment: the
/// bitmap backend joins wide polylines with unlimited miters, which spike
/// far out of the chart at the sharp turns of noisy data.
fn stroke<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    px: &[(i32, i32)],
    style: ShapeStyle,
    line: Line,
    segmented: bool,
) -> Result<(), PlotError> {
    let pieces = match line {
        Line::Hidden => return Ok(()),
        Line::Solid => vec![px.to_vec()],
        Line::Dashed => dashes(px, 9.0, 5.0),
        Line::Dotted => dashes(px, 3.0, 4.0),
    };
    for piece in pieces {
        if piece.len() < 2 {
            continue;
        }
        if segmented {
            for w in piece.windows(2) {
                area.draw(&PathElement::new(vec![w[0], w[1]], style))
                    .map_err(draw_err)?;
            }
        } else {
            area.draw(&PathElement::new(piece, style))
                .map_err(draw_err)?;
        }
    }
    Ok(())
}

/// Corners of a polygonal marker of radius `r` around `at` (empty for
/// the others).
fn marker_corners(marker: Marker, at: (i32, i32), r: i32) -> Vec<(i32, i32)> {
    let (x, y) = at;
    let around = |degrees: [f64; 3]| {
        degrees
            .iter()
            .map(|d| {
                let a = d.to_radians();
                (
                    (f64::from(x) + f64::from(r) * a.cos()).round() as i32,
                    (f64::from(y) + f64::from(r) * a.sin()).round() as i32,
                )
            })
            .collect()
    };
    match marker {
        Marker::Triangle => around([-90.0, 30.0, 150.0]),
        Marker::TriangleDown => around([90.0, 210.0, 330.0]),
        Marker::Square => {
            let h = r * 2 / 3;
            vec![
                (x - h, y - h),
                (x + h, y - h),
                (x + h, y + h),
                (x - h, y + h),
            ]
        }
        Marker::Diamond => vec![(x, y - r), (x + r, y), (x, y + r), (x - r, y)],
        Marker::Hexagon => {
            let hex: [f64; 6] = [-90.0, -30.0, 30.0, 90.0, 150.0, 210.0];
            hex.iter()
                .map(|d| {
                    let a = d.to_radians();
                    (
                        (f64::from(x) + f64::from(r - 1) * a.cos()).round() as i32,
                        (f64::from(y) + f64::from(r - 1) * a.sin()).round() as i32,
                    )
                })
                .collect()
        }
        Marker::Star => (0..10)
            .map(|k| {
                let a = (-90.0 + 36.0 * f64::from(k)).to_radians();
                let rho = if k % 2 == 0 {
                    f64::from(r)
                } else {
                    0.45 * f64::from(r)
                };
                (
                    (f64::from(x) + rho * a.cos()).round() as i32,
                    (f64::from(y) + rho * a.sin()).round() as i32,
                )
            })
            .collect(),
        Marker::None | Marker::Circle | Marker::Cross | Marker::Plus => Vec::new(),
    }
}

/// Draw a look's marker in its marker colour: filled, or (`hollow`) its
/// outline on white, a little larger, so that the line under it does not
/// show.
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    look: &Look,
) -> Result<(), PlotError> {
    let (marker, hollow) = (look.marker, look.hollow);
    let style = ShapeStyle {
        color: look.marker_color.to_rgba(),
        filled: false,
        stroke_width: look.width,
    };
    let filled = style.filled();
    // Radius of the polygonal markers (the square's half side is 2/3 of it).
    let r = 6;
    match marker {
        Marker::None => Ok(()),
        Marker::Circle if hollow => {
            area.draw(&Circle::new(at, 5, WHITE.filled()))
                .map_err(draw_err)?;
            area.draw(&Circle::new(at, 5, style)).map_err(draw_err)
        }
        Marker::Circle => area.draw(&Circle::new(at, 4, filled)).map_err(draw_err),
        Marker::Cross | Marker::Plus => {
            let d = if marker == Marker::Cross {
                r * 2 / 3
            } else {
                r
            };
            let arms = if marker == Marker::Cross {
                [
                    ((at.0 - d, at.1 - d), (at.0 + d, at.1 + d)),
                    ((at.0 - d, at.1 + d), (at.0 + d, at.1 - d)),
                ]
            } else {
                [
                    ((at.0 - d, at.1), (at.0 + d, at.1)),
                    ((at.0, at.1 - d), (at.0, at.1 + d)),
                ]
            };
            let style = ShapeStyle {
                stroke_width: look.width.max(2) + 1,
                ..style
            };
            for (a, b) in arms {
                area.draw(&PathElement::new(vec![a, b], style))
                    .map_err(draw_err)?;
            }
            Ok(())
        }
        _ => {
            let corners = marker_corners(marker, at, if hollow { r + 1 } else { r });
            if hollow {
                area.draw(&Polygon::new(corners.clone(), WHITE.filled()))
                    .map_err(draw_err)?;
                let mut closed = corners.clone();
                closed.extend(corners.first().copied());
                area.draw(&PathElement::new(closed, style))
                    .map_err(draw_err)
            } else {
                area.draw(&Polygon::new(corners, filled)).map_err(draw_err)
            }
        }
    }
}

fn fill<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    p: &Panel,
    x_span: (f64, f64),
    y_span: (f64, f64),
    segmented: bool,
) -> Result<(), PlotError>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let x_fmt = |v: &f64| {
        if p.x_log {
            log_tick(*v)
        } else {
            lin_tick(*v, x_span.1 - x_span.0)
        }
    };
    let y_fmt = |v: &f64| {
        if p.y_log {
            log_tick(*v)
        } else {
            lin_tick(*v, y_span.1 - y_span.0)
        }
    };
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .x_labels(8)
        .y_labels(if p.y_log { 20 } else { 6 })
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(BLACK.mix(0.04))
        .draw()
        .map_err(draw_err)?;
    let area = chart.plotting_area();
    let screen = area.use_screen_coord();
    for (k, s) in p.series.iter().enumerate() {
        let style = ShapeStyle {
            color: s.look.color.to_rgba(),
            filled: false,
            stroke_width: s.look.width,
        };
        let mut px: Vec<(i32, i32)> = s
            .points
            .iter()
            .filter(|(x, y)| x.is_finite() && y.is_finite() && (!p.x_log || *x > 0.0))
            .filter(|(_, y)| !(p.y_log && p.drop_zeros && *y <= 0.0))
            .map(|&(x, y)| area.map_coordinate(&(x, if p.y_log { y.max(y_span.0) } else { y })))
            .collect();
        px.dedup();
        stroke(&screen, &px, style, s.look.line, segmented)?;
        match p.markers {
            Markers::None => {}
            Markers::Every => {
                for q in &px {
                    draw_marker(&screen, *q, &s.look)?;
                }
            }
            Markers::Sparse if px.len() > 1 => {
                // About a dozen per curve, each curve's shifted by a
                // fraction of the spacing so coinciding curves show all.
                let every = (px.len() / 12).max(1);
                let shift = (k * every / p.series.len().max(1)) % every;
                for q in px.iter().skip(shift).step_by(every) {
                    draw_marker(&screen, *q, &s.look)?;
                }
            }
            Markers::Sparse => {
                for q in &px {
                    draw_marker(&screen, *q, &s.look)?;
                }
            }
        }
        for (i, text) in &s.labels {
            let Some(&(x, y)) = s.points.get(*i) else {
                continue;
            };
            if !(x.is_finite() && y.is_finite()) || (p.x_log && x <= 0.0) || (p.y_log && y <= 0.0) {
                continue;
            }
            let (sx, sy) = area.map_coordinate(&(x, y));
            let font = ("sans-serif", 12).into_font().color(&s.look.color);
            screen
                .draw(&Text::new(text.clone(), (sx + 6, sy - 14), font))
                .map_err(draw_err)?;
        }
    }
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    segmented: bool,
) -> Result<(), PlotError> {
    let xs = range(
        p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0)),
        p.x_log,
    );
    let ys = range(
        p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1)),
        p.y_log,
    );
    let ((x0, x1), (y0, y1)) = (xs, ys);
    let mut b = ChartBuilder::on(area);
    b.caption(p.title.as_str(), ("sans-serif", 17))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(if p.y_log { 86 } else { 80 });
    match (p.x_log, p.y_log) {
        (false, false) => {
            let mut c = b.build_cartesian_2d(x0..x1, y0..y1).map_err(draw_err)?;
            fill::<DB, RangedCoordf64, RangedCoordf64>(&mut c, p, xs, ys, segmented)
        }
        (false, true) => {
            let mut c = b
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(draw_err)?;
            fill(&mut c, p, xs, ys, segmented)
        }
        (true, false) => {
            let mut c = b
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(draw_err)?;
            fill(&mut c, p, xs, ys, segmented)
        }
        (true, true) => {
            let mut c = b
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(draw_err)?;
            fill(&mut c, p, xs, ys, segmented)
        }
    }
}

fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, Look, bool)],
    segmented: bool,
) -> Result<(), PlotError> {
    let font = ("sans-serif", 15).into_font();
    area.draw(&Text::new(
        "legend",
        (12, 14),
        ("sans-serif", 16).into_font().style(FontStyle::Bold),
    ))
    .map_err(draw_err)?;
    for (i, (text, lk, marker)) in entries.iter().enumerate() {
        let y = 48 + 26 * i as i32;
        let style = ShapeStyle {
            color: lk.color.to_rgba(),
            filled: false,
            stroke_width: lk.width,
        };
        if lk.line == Line::Hidden && !*marker {
            // A heading of the compact legend.
            let bold = ("sans-serif", 15).into_font().style(FontStyle::Bold);
            area.draw(&Text::new(text.as_str(), (12, y - 8), bold))
                .map_err(draw_err)?;
            continue;
        }
        stroke(area, &[(12, y), (58, y)], style, lk.line, segmented)?;
        if *marker {
            draw_marker(area, (35, y), lk)?;
        }
        area.draw(&Text::new(text.as_str(), (68, y - 8), font.clone()))
            .map_err(draw_err)?;
    }
    Ok(())
}

/// Draw a figure on any backend; `segmented` strokes lines segment by
/// segment (for the bitmap backend, whose thick lines are drawn as quads).
pub fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    segmented: bool,
) -> Result<(), PlotError> {
    crate::font::register()?;
    root.fill(&WHITE).map_err(draw_err)?;
    let (top, body) = root.split_vertically(TITLE_HEIGHT);
    top.draw(&Text::new(
        fig.title.as_str(),
        (16, 12),
        ("sans-serif", 22).into_font().style(FontStyle::Bold),
    ))
    .map_err(draw_err)?;
    let (w, _) = body.dim_in_pixel();
    // Wider than LEGEND_WIDTH when a label needs it (the reference lines'
    // `MEBDF maxder5 (Fortran, rcd1)`).
    let font: TextStyle = ("sans-serif", 15).into_font().into();
    let widest = fig
        .legend
        .iter()
        .filter_map(|(text, _, _)| root.estimate_text_size(text, &font).ok())
        .map(|(tw, _)| tw + 68 + 12)
        .max()
        .unwrap_or(0);
    let legend_w = LEGEND_WIDTH.max(widest).min(w / 2);
    let (plots, legend) = body.split_horizontally(w.saturating_sub(legend_w));
    let cols = fig.cols.max(1);
    let rows = fig.panels.len().div_ceil(cols).max(1);
    let areas = plots.split_evenly((rows, cols));
    for (p, a) in fig.panels.iter().zip(&areas) {
        draw_panel(a, p, segmented)?;
    }
    draw_legend(&legend, &fig.legend, segmented)?;
    Ok(())
}

/// Write a figure as `DIR/<file>.svg` and `DIR/<file>.png`, each whole.
pub fn render(fig: &Figure, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let svg_path = dir.join(format!("{}.svg", fig.file));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, fig.size).into_drawing_area();
        draw(&root, fig, false)?;
        root.present().map_err(draw_err)?;
    }
    write::atomic_write(&svg_path, svg.as_bytes())?;
    let png_path = dir.join(format!("{}.png", fig.file));
    write::atomic_write_via(&png_path, |tmp: &Path| -> Result<(), PlotError> {
        let root = BitMapBackend::new(tmp, fig.size).into_drawing_area();
        draw(&root, fig, true)?;
        root.present().map_err(draw_err)?;
        Ok(())
    })?;
    Ok(vec![svg_path, png_path])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_colour_per_solver_and_one_marker_per_formulation() {
        let solvers = dae_solvers::SOLVER_NAMES;
        let formulations = dae_core::system::FORMULATION_NAMES;
        for (i, a) in solvers.iter().enumerate() {
            for b in &solvers[i + 1..] {
                assert_ne!(solver_color(a), solver_color(b), "{a} and {b}");
            }
            // The Fortran lines' greys are not a solver's colour.
            for code in [
                "radau5",
                "dassl",
                "daspk",
                "odassl",
                "mebdf",
                "mebdf-maxder5",
            ] {
                assert_ne!(reference_look(code, "rcd0").color, solver_color(a));
            }
        }
        for (i, a) in formulations.iter().enumerate() {
            for b in &formulations[i + 1..] {
                assert_ne!(formulation_marker(a), formulation_marker(b), "{a} and {b}");
            }
            assert_ne!(formulation_marker(a), Marker::None);
        }
        // The same look in every figure: colour from the solver alone,
        // marker from the formulation alone.
        for s in solvers {
            for f in formulations {
                let lk = look(s, f);
                assert_eq!(lk.color, solver_color(s));
                assert_eq!(lk.marker, formulation_marker(f));
                assert_eq!(reference_look(s, f).marker, formulation_marker(f));
            }
        }
    }

    #[test]
    fn the_legend_is_compact() {
        let solvers: Vec<String> = dae_solvers::SOLVER_NAMES.map(String::from).to_vec();
        let formulations: Vec<String> = dae_core::system::FORMULATION_NAMES
            .map(String::from)
            .to_vec();
        // 63 pairs: 2 headings + 7 + 9 entries.
        let legend = compact_legend(&solvers, &formulations, true);
        assert_eq!(legend.len(), 18);
        assert!(legend
            .iter()
            .any(|(l, lk, _)| l == "mebdf" && lk.color == solver_color("mebdf")));
        assert!(legend
            .iter()
            .any(|(l, lk, m)| l == "psi1" && lk.marker == Marker::Plus && *m));
    }
}
