//! `index.html`: the tables and figures of a sweep on one self-contained
//! page (inline CSS, no JavaScript, figures linked relatively).

use super::fortran::ReferenceLines;
use super::paper::Verdict;
use super::pareto;
use super::plot::Figure;
use super::table::{
    accuracy_line, efficiency_rows, front_ties, paper_cell, sci, tied_text, tol_label,
    USABLE_LEGEND,
};
use super::{Summary, SweepReport};
use std::fmt::Write;

/// Escape text for HTML.
pub fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

const STYLE: &str = "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:2em auto;max-width:1500px;\
padding:0 1em;color:#222}h1{font-size:1.6em}h2{margin-top:2em;border-bottom:1px solid #ccc}\
table{border-collapse:collapse;margin:.5em 0;font-size:.9em}th,td{border:1px solid #ccc;padding:.25em .6em;\
text-align:right;white-space:nowrap}th{background:#f3f3f3}td.l,th.l{text-align:left}\
td.acc-all{background:#cdeccd}td.acc-some{background:#ffe9a8}td.acc-none{background:#f6c4c4}\
td.na{background:#eee;color:#666}span.sw{display:inline-block;width:1em;height:1em;vertical-align:middle;\
border:1px solid #999;margin:0 .2em 0 .6em}nav#toc{background:#f7f7f7;border:1px solid #ddd;padding:.3em 1em;\
display:inline-block}nav#toc ol{margin:.3em 0;padding-left:1.4em}nav#toc li{margin:.1em 0}\
td.fail{color:#a00}td.more{background:#d8f0d8}td.eq{background:#eef}td.behind{background:#f8d0d0}\
figure{margin:1.5em 0}figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:.9em;color:#444}\
.note{background:#fff8e0;border-left:4px solid #e0b000;padding:.4em .8em}\
small.bad{color:#a00;font-weight:bold}.scroll{overflow-x:auto}table.paper{font-size:.78em}\
table.paper td{padding:.2em .4em;line-height:1.25}\
code{background:#f3f3f3;padding:0 .2em}";

fn table(rows: &[Vec<String>], left_cols: usize) -> String {
    let mut s = String::from("<div class=\"scroll\"><table>\n");
    for (i, r) in rows.iter().enumerate() {
        s.push_str("<tr>");
        for (c, cell) in r.iter().enumerate() {
            let tag = if i == 0 { "th" } else { "td" };
            let class = if c < left_cols { " class=\"l\"" } else { "" };
            let _ = write!(s, "<{tag}{class}>{}</{tag}>", esc(cell));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table></div>\n");
    s
}

fn success_html(summary: &Summary) -> String {
    let m = &summary.success;
    let reasons = m.reasons();
    let mut failures: Vec<String> = Vec::new();
    let mut s = String::from("<table>\n<tr><th class=\"l\"></th>");
    for f in &m.formulations {
        let _ = write!(s, "<th>{}</th>", esc(f));
    }
    s.push_str("</tr>\n");
    for r in &m.rows {
        let _ = write!(s, "<tr><th class=\"l\">{}</th>", esc(&r.solver));
        for c in &r.cells {
            match (&c.reason, c.mark) {
                (Some(why), _) => {
                    let n = reasons.iter().position(|x| x == why).map_or(0, |i| i + 1);
                    let _ = write!(
                        s,
                        "<td class=\"na\" title=\"{}\">-<sup>{n}</sup></td>",
                        esc(why)
                    );
                }
                (None, mark) => {
                    let class = c.usable().class();
                    let warn = c.inaccurate + c.suspect > 0;
                    let note = c.failure_note().map_or_else(String::new, |note| {
                        failures.push(format!("{}({}) {note}", r.solver, c.formulation));
                        format!("<sup>*{}</sup>", failures.len())
                    });
                    let _ = write!(
                        s,
                        "<td class=\"{class}\" title=\"reached the end at {} of {} tolerances; accurate {}, \
                         inaccurate {}, unverified {}, suspect {}\">{}{note}<br><small{}>{}</small></td>",
                        c.ok,
                        c.runs,
                        c.accurate,
                        c.inaccurate,
                        c.unverified,
                        c.suspect,
                        mark.symbol(),
                        if warn { " class=\"bad\"" } else { "" },
                        esc(&c.accuracy_label())
                    );
                }
            }
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n<p>");
    for (i, r) in reasons.iter().enumerate() {
        let _ = write!(s, "<sup>{}</sup> {}<br>", i + 1, esc(r));
    }
    for (i, f) in failures.iter().enumerate() {
        let _ = write!(s, "<sup>*{}</sup> {}<br>", i + 1, esc(f));
    }
    let _ = writeln!(s, "{}</p>", esc(m.legend));
    let _ = writeln!(
        s,
        "<p class=\"legend\"><span class=\"sw\" style=\"background:#cdeccd\"></span>every tolerance usable\
         <span class=\"sw\" style=\"background:#ffe9a8\"></span>some\
         <span class=\"sw\" style=\"background:#f6c4c4\"></span>none\
         <span class=\"sw\" style=\"background:#eee\"></span>not applicable. {}</p>",
        esc(USABLE_LEGEND)
    );
    s
}

/// The table of contents: the page's sections and figures, as links to
/// their anchors.
fn toc(report: &SweepReport, figures: &[&Figure]) -> String {
    let mut s = String::from("<nav id=\"toc\"><strong>Contents</strong>\n<ol>\n");
    s.push_str("<li><a href=\"#success\">Success matrix</a></li>\n");
    if report.has_reference() {
        s.push_str(
            "<li><a href=\"#trade\">The trade</a>: <a href=\"#pareto\">Pareto front</a>, \
             <a href=\"#targets\">fastest run per target error</a></li>\n",
        );
    } else {
        s.push_str("<li><a href=\"#trade\">The trade</a> (no reference)</li>\n");
    }
    s.push_str("<li><a href=\"#paper\">Against the paper</a></li>\n");
    s.push_str("<li><a href=\"#figures\">Figures</a>");
    if !figures.is_empty() {
        let items: Vec<String> = figures
            .iter()
            .map(|f| format!("<a href=\"#fig-{0}\">{0}</a>", esc(&f.file)))
            .collect();
        let _ = write!(s, ": {}", items.join(", "));
    }
    s.push_str("</li>\n<li><a href=\"#efficiency\">Efficiency</a> (every run)</li>\n</ol></nav>\n");
    s
}

fn paper_html(summary: &Summary) -> String {
    let Some(c) = &summary.paper else {
        return "<p>Only for the paper's scenes S01 and S02 (built-in pendulum, paper Tables 6 and 9).</p>\n".into();
    };
    let mut s = comparison_html(c);
    if let Some(c) = &summary.paper_l2 {
        s.push_str("<h3 id=\"paper-l2\">Like for like</h3>\n");
        s.push_str(&comparison_html(c));
    }
    s
}

fn comparison_html(c: &super::paper::Comparison) -> String {
    let mut tols: Vec<f64> = Vec::new();
    for cell in c.rows.iter().flat_map(|r| &r.cells) {
        if !tols.iter().any(|t| super::paper::same_tol(*t, cell.tol)) {
            tols.push(cell.tol);
        }
    }
    let mut s = format!("<p>{}: {}</p>\n<div class=\"scroll\"><table class=\"paper\">\n<tr><th class=\"l\">ours</th><th class=\"l\">paper</th>", esc(&c.table), esc(&c.note));
    for t in &tols {
        let _ = write!(s, "<th>{}</th>", tol_label(*t));
    }
    s.push_str("</tr>\n");
    for r in &c.rows {
        let _ = write!(
            s,
            "<tr><td class=\"l\">{}({})</td><td class=\"l\">{}({})</td>",
            esc(&r.solver),
            esc(&r.formulation),
            esc(&r.paper_solver),
            esc(&r.formulation)
        );
        for t in &tols {
            match r.cells.iter().find(|c| super::paper::same_tol(c.tol, *t)) {
                Some(cell) => {
                    let class = match cell.verdict {
                        Verdict::MoreAccurate | Verdict::PaperFailed => "more",
                        Verdict::Equal => "eq",
                        Verdict::Behind | Verdict::WeFailed => "behind",
                        _ => "na",
                    };
                    let ours = cell
                        .ours
                        .map_or_else(|| "failed".to_string(), |v| sci(Some(v)));
                    let _ = write!(
                        s,
                        "<td class=\"{class}\">{}<br>{}<br><small>{}</small></td>",
                        esc(&ours),
                        esc(&paper_cell(cell.paper)),
                        cell.verdict.label()
                    );
                }
                None => s.push_str("<td></td>"),
            }
        }
        s.push_str("</tr>\n");
    }
    let _ = write!(
        s,
        "</table></div>\n<p>Cells: ours ({}), the paper's ERR below it, the verdict. ",
        c.measure.field()
    );
    let counts: Vec<String> = c
        .counts
        .iter()
        .filter(|k| k.cells > 0)
        .map(|k| format!("{} {}", k.cells, k.verdict.label()))
        .collect();
    let _ = writeln!(s, "{}.</p>", esc(&counts.join(", ")));
    if !c.illegible.is_empty() {
        let _ = writeln!(
            s,
            "<p>Illegible in the seed text, not compared: {}.</p>",
            esc(&c.illegible.join(", "))
        );
    }
    s
}

/// The paragraph on the Fortran reference lines of the work-precision
/// diagram: which codes, where from, how many points, where they failed.
fn reference_lines_html(lines: &ReferenceLines) -> String {
    let mut s = format!(
        "<p id=\"fortran\">The work-precision diagram carries {} Fortran reference line(s) for {}: ",
        lines.curves.len(),
        lines.scenario.name()
    );
    let items: Vec<String> = lines
        .curves
        .iter()
        .map(|c| {
            let mut item = format!(
                "{} ({} point(s), {} of data/{}",
                c.label,
                c.points.len(),
                c.time_column,
                c.files.join(" and data/")
            );
            if !c.failed.is_empty() {
                let tols: Vec<String> = c.failed.iter().map(|t| tol_label(*t)).collect();
                let _ = write!(item, "; failed at {}", tols.join(", "));
            }
            item.push(')');
            item
        })
        .collect();
    let _ = writeln!(
        s,
        "{}. They were measured in another session, not by this sweep: errors compare exactly, times only \
         roughly (see the caption of the diagram).</p>",
        esc(&items.join("; "))
    );
    s
}

/// The page.
pub fn index(
    report: &SweepReport,
    summary: &Summary,
    figures: &[&Figure],
    notes: &[String],
) -> String {
    let sc = &report.scene;
    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>dae sweep {}</title>\n\
         <style>{STYLE}</style>\n</head>\n<body>\n<h1>dae sweep — {}</h1>\n",
        esc(&sc.name),
        esc(&sc.name)
    );
    let _ = writeln!(
        s,
        "<p>Scene <code>{}</code>: model <code>{}</code>, t ∈ [{}, {}] s, {} check time(s), reference \
         <code>{}</code>. {} (RTOL = ATOL). Data: <a href=\"results.csv\">results.csv</a>, \
         <a href=\"results.json\">results.json</a>.</p>",
        esc(&sc.origin),
        esc(&sc.model),
        sc.t0,
        sc.t_end,
        sc.checks,
        esc(sc.reference),
        esc(&report.scale_line())
    );
    s.push_str(&toc(report, figures));
    for n in notes {
        let _ = writeln!(s, "<p class=\"note\">{}</p>", esc(n));
    }
    s.push_str("<h2 id=\"success\">Success matrix</h2>\n");
    s.push_str(&success_html(summary));
    let _ = writeln!(s, "<p class=\"note\">{}</p>", esc(&accuracy_line(report)));
    if report.has_reference() {
        s.push_str(
            "<h2 id=\"trade\">The trade</h2>\n<p>Both summaries use <code>err</code>, the largest pointwise error of the \
             differential unknowns over the check times, and tsim, the CPU time of the integrating thread (so the load \
             of the machine as a whole does not move the ranking; wall_s is in the efficiency table). ",
        );
        let _ = writeln!(
            s,
            "{} {}</p>",
            esc(pareto::TARGET_RULE),
            esc(pareto::FRONT_RULE)
        );
        let mut rows = vec![vec![
            "pair".to_string(),
            "tol".into(),
            "tsim_s".into(),
            "err".into(),
            "≈".into(),
        ]];
        rows.extend(
            summary
                .pareto
                .iter()
                .zip(front_ties(&summary.pareto))
                .map(|(p, m)| {
                    vec![
                        p.pair(),
                        tol_label(p.tol),
                        sci(Some(p.tsim_s)),
                        sci(Some(p.err)),
                        m.to_string(),
                    ]
                }),
        );
        s.push_str("<h3 id=\"pareto\">Pareto front</h3>\n");
        s.push_str(&table(&rows, 1));
        s.push_str("<h3 id=\"targets\">Fastest run per target error</h3>\n");
        let mut rows = vec![vec![
            "target err".to_string(),
            "fastest pair".into(),
            "tol".into(),
            "tsim_s".into(),
            "err".into(),
            format!(
                "tied with (time within {} %)",
                100.0 * pareto::TIME_RESOLUTION
            ),
        ]];
        for t in &summary.targets {
            let mut r = vec![format!("≤ {}", sci(Some(t.target)))];
            match &t.best {
                Some(p) => r.extend([
                    p.pair(),
                    tol_label(p.tol),
                    sci(Some(p.tsim_s)),
                    sci(Some(p.err)),
                    tied_text(t),
                ]),
                None => r.extend([
                    "none met it".to_string(),
                    String::new(),
                    String::new(),
                    String::new(),
                    String::new(),
                ]),
            }
            rows.push(r);
        }
        s.push_str(&table(&rows, 2));
    } else {
        s.push_str(
            "<h2 id=\"trade\">The trade</h2>\n<p class=\"note\">This scene has no reference (<code>[reference] kind = \
             \"none\"</code>): errors are not measured, so there is no Pareto front and no target table. Residuals \
             and drift are reported below.</p>\n",
        );
    }
    s.push_str("<h2 id=\"paper\">Against the paper</h2>\n");
    s.push_str(&paper_html(summary));
    s.push_str("<h2 id=\"figures\">Figures</h2>\n");
    let drawn_wp = figures.iter().any(|f| f.file == "work_precision");
    if let Some(lines) = summary.reference_lines.as_ref().filter(|_| drawn_wp) {
        s.push_str(&reference_lines_html(lines));
    }
    for f in figures {
        let alt = match &summary.reference_lines {
            Some(lines) if f.file == "work_precision" => format!(
                "{}; dotted grey lines with hollow markers: {} Fortran reference curve(s) on this scene ({}), \
                 measured in another session on a machine of the same class",
                f.title,
                lines.curves.len(),
                lines.scenario.name()
            ),
            _ => f.title.clone(),
        };
        let _ = writeln!(
            s,
            "<figure id=\"fig-{0}\"><a href=\"{0}.svg\"><img src=\"{0}.svg\" alt=\"{1}\"></a><figcaption>{2} \
             (<a href=\"{0}.svg\">SVG</a>, <a href=\"{0}.png\">PNG</a>)</figcaption></figure>",
            esc(&f.file),
            esc(&alt),
            esc(&f.caption)
        );
    }
    let inv = report.invariants.first().map_or("I", String::as_str);
    let _ = write!(
        s,
        "<h2 id=\"efficiency\">Efficiency</h2>\n<p>One row per run. tsim_s: integration time in seconds, the CPU time of the integrating thread (minimum of \
         the timed integrations, at least the sweep's repeats, more for short runs and until three lie within 1 % of \
         the minimum: interference only adds time; the Pareto front and the fastest pairs use it, times within 5 % tied); wall_s: the wall-clock time of the \
         same integrations (their minimum); err: largest pointwise \
         error of the differential unknowns over the reference's times; err_sum: sum over those times of the errors \
         of all unknowns the reference gives (SPEC's reading of the paper's ERR; results.csv also has err_l2, their \
         Euclidean norm); err_alg: largest error of the algebraic \
         unknowns (multipliers); evals / jac / LU: \
         residual and Jacobian evaluations and LU factorisations; |gk|: largest residual of the level-k \
         constraints over the check times; drift: largest |{0}(t) − {0}(t0)|.</p>\n",
        esc(inv)
    );
    s.push_str(&table(&efficiency_rows(&report.runs), 1));
    s.push_str("</body>\n</html>\n");
    s
}
