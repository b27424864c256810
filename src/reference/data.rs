//! References as data: what a run's numerical solution is compared
//! against, for any model.
//!
//! A [`Reference`] gives values of some unknowns (by name; any subset, in
//! any order) and says how each one's error is measured ([`Scaling`]). It
//! comes in three kinds:
//!
//! - **`exact`**: a built-in closed form, evaluated at every check time
//!   (today the pendulum's, [`super::PendulumExact`]);
//! - **`values`**: published values at a few given times — the IVP Test
//!   Set's reference solution at the end point, say. Errors are measured at
//!   those times, not at the scene's check times;
//! - **`trajectory`**: a solution sampled in time (a CSV file), interpolated
//!   at the check times by cubic Lagrange interpolation through the four
//!   nearest samples.
//!
//! Values and trajectories are [`Table`]s, read from CSV (`t` and one
//! column per unknown) or given inline in a scene.
//!
//! ```
//! use dae::reference::data::{Reference, Scaling, Table};
//!
//! let table = Table::from_csv("t,x,lambda\n0.5,0.25,2.0\n1.0,1.0,4.0\n").unwrap();
//! let reference = Reference::values(table, vec![Scaling::Absolute, Scaling::Relative]);
//! assert_eq!(reference.names(), ["x", "lambda"]);
//! assert_eq!(reference.times(), Some(&[0.5, 1.0][..]));
//! let mut exact = [0.0; 2];
//! assert!(reference.at(1.0, &mut exact));
//! assert_eq!(exact, [1.0, 4.0]);
//! // lambda's error is relative: |4.4 − 4| / 4.
//! assert!((Scaling::Relative.error(4.4, 4.0) - 0.1).abs() < 1e-15);
//! ```

use super::PendulumExact;
use serde::Serialize;
use std::fmt;

/// How the error of one reference component is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scaling {
    /// `|y − y*|`.
    Absolute,
    /// `|y − y*| / |y*|`, and `|y − y*|` where `y* = 0` (the IVP Test Set's
    /// convention; its *significant correct digits* are `−log₁₀` of the
    /// largest relative error, [`crate::runner::RunRecord::scd`]).
    Relative,
}

/// Names of the scalings, as scene files write them.
pub const SCALINGS: [&str; 2] = ["absolute", "relative"];

impl Scaling {
    /// The scaling named `name` ([`SCALINGS`]).
    pub fn parse(name: &str) -> Option<Scaling> {
        match name {
            "absolute" => Some(Scaling::Absolute),
            "relative" => Some(Scaling::Relative),
            _ => None,
        }
    }

    /// The name used in scene files.
    pub fn as_str(self) -> &'static str {
        match self {
            Scaling::Absolute => "absolute",
            Scaling::Relative => "relative",
        }
    }

    /// The error of `y` against the reference value `exact`.
    pub fn error(self, y: f64, exact: f64) -> f64 {
        let d = (y - exact).abs();
        match self {
            Scaling::Relative if exact != 0.0 => d / exact.abs(),
            _ => d,
        }
    }
}

/// Reference values at given times: `rows[i][j]` is unknown `names[j]` at
/// `times[i]`. Times strictly increase; every value is finite.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table {
    /// Unknowns, one per column.
    pub names: Vec<String>,
    /// Times, strictly increasing.
    pub times: Vec<f64>,
    /// One row of values per time.
    pub rows: Vec<Vec<f64>>,
}

/// Why a reference table was refused: the line (1-based, of the CSV text;
/// 0 for an inline table) and what is wrong.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{reason}", if *.line > 0 { format!("line {}: ", .line) } else { String::new() })]
pub struct TableError {
    /// 1-based line of the CSV text (0: not tied to a line).
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

fn table_error(line: usize, reason: impl Into<String>) -> TableError {
    TableError {
        line,
        reason: reason.into(),
    }
}

impl Table {
    /// A table from columns, checked: at least one name and one time, no
    /// name twice, times strictly increasing, every row as long as `names`,
    /// every number finite.
    pub fn new(
        names: Vec<String>,
        times: Vec<f64>,
        rows: Vec<Vec<f64>>,
    ) -> Result<Table, TableError> {
        let table = Table { names, times, rows };
        table.check(&vec![0; table.times.len()])?;
        Ok(table)
    }

    /// Check the table; `lines[i]` is the text line of row `i` (0 inline).
    fn check(&self, lines: &[usize]) -> Result<(), TableError> {
        if self.names.is_empty() {
            return Err(table_error(
                0,
                "no unknowns: give at least one column besides `t`",
            ));
        }
        for (j, n) in self.names.iter().enumerate() {
            if n.is_empty() {
                return Err(table_error(0, format!("column {} has no name", j + 2)));
            }
            if self.names[..j].contains(n) {
                return Err(table_error(0, format!("unknown `{n}` given twice")));
            }
        }
        if self.times.is_empty() {
            return Err(table_error(0, "no values: give at least one time"));
        }
        for (i, (t, row)) in self.times.iter().zip(&self.rows).enumerate() {
            let line = lines.get(i).copied().unwrap_or(0);
            if !t.is_finite() {
                return Err(table_error(line, format!("time {t} is not finite")));
            }
            if i > 0 && *t <= self.times[i - 1] {
                return Err(table_error(
                    line,
                    format!(
                        "times must increase strictly: {t} after {}",
                        self.times[i - 1]
                    ),
                ));
            }
            if row.len() != self.names.len() {
                return Err(table_error(
                    line,
                    format!("{} values for {} unknowns", row.len(), self.names.len()),
                ));
            }
            if let Some((j, v)) = row.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(table_error(
                    line,
                    format!("value {v} of `{}` is not finite", self.names[j]),
                ));
            }
        }
        if self.rows.len() != self.times.len() {
            return Err(table_error(
                0,
                format!("{} rows for {} times", self.rows.len(), self.times.len()),
            ));
        }
        Ok(())
    }

    /// Read a CSV text (RFC 4180, by the `csv` crate): a header
    /// `t,name,…` (the first column must be called `t`), then one row of
    /// numbers per time. Blank lines and lines starting with `#` are
    /// skipped; cells may be padded with spaces. A refusal names the line
    /// and, for a cell, its column.
    ///
    /// ```
    /// use dae::reference::data::Table;
    ///
    /// let t = Table::from_csv("# a comment\nt, x\n0, 1\n\n1, 2\n").unwrap();
    /// assert_eq!((t.times, t.rows), (vec![0.0, 1.0], vec![vec![1.0], vec![2.0]]));
    /// let e = Table::from_csv("t,x\n0,1\n1,oops\n").unwrap_err();
    /// assert_eq!(e.to_string(), "line 3: column `x`: `oops` is not a number");
    /// ```
    pub fn from_csv(text: &str) -> Result<Table, TableError> {
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(text.as_bytes());
        // Records with their 1-based lines, without blank or commented
        // lines (the reader skips those starting with `#` only at the
        // first byte; indented ones are skipped here).
        let mut records = reader.records().filter_map(|record| {
            let record = match record {
                Ok(r) => r,
                Err(e) => {
                    let line = e.position().map_or(0, |p| p.line() as usize);
                    return Some(Err(table_error(line, e.to_string())));
                }
            };
            let line = record.position().map_or(0, |p| p.line() as usize);
            let blank = record.iter().all(str::is_empty);
            let comment = record.get(0).is_some_and(|c| c.starts_with('#'));
            (!blank && !comment).then_some(Ok((line, record)))
        });
        let (header_line, header) = records
            .next()
            .ok_or_else(|| table_error(0, "empty: expected a header `t,<unknown>,…`"))??;
        if header.get(0) != Some("t") {
            return Err(table_error(
                header_line,
                "the first column must be `t` (header `t,<unknown>,…`)",
            ));
        }
        let names: Vec<String> = header.iter().skip(1).map(str::to_string).collect();
        let column = |col: usize| match col {
            0 => "`t`".to_string(),
            c => names
                .get(c - 1)
                .map_or_else(|| format!("{}", c + 1), |n| format!("`{n}`")),
        };
        let (mut times, mut rows, mut at) = (Vec::new(), Vec::new(), Vec::new());
        for record in records {
            let (line, record) = record?;
            let mut values = Vec::with_capacity(names.len() + 1);
            for (col, cell) in record.iter().enumerate() {
                let v: f64 = cell.parse().map_err(|_| {
                    table_error(
                        line,
                        format!("column {}: `{cell}` is not a number", column(col)),
                    )
                })?;
                values.push(v);
            }
            times.push(values[0]);
            rows.push(values[1..].to_vec());
            at.push(line);
        }
        let table = Table { names, times, rows };
        if table.names.is_empty() {
            return Err(table_error(
                header_line,
                "no unknowns: give at least one column besides `t`",
            ));
        }
        table.check(&at).map_err(|mut e| {
            if e.line == 0 && !table.times.is_empty() {
                e.line = header_line;
            }
            e
        })?;
        Ok(table)
    }

    /// The row given at `t` (within `10⁻¹²(1 + |t|)`), if any.
    pub fn row_at(&self, t: f64) -> Option<&[f64]> {
        let slack = 1e-12 * (1.0 + t.abs());
        let i = self.times.partition_point(|&s| s < t - slack);
        (i < self.times.len() && self.times[i] <= t + slack).then(|| &self.rows[i][..])
    }

    /// Cubic Lagrange interpolation through the (up to) four samples
    /// nearest to `t`; `false` outside `[times[0], times[last]]`.
    pub fn interpolate(&self, t: f64, out: &mut [f64]) -> bool {
        let n = self.times.len();
        let (first, last) = (self.times[0], self.times[n - 1]);
        let slack = 1e-12 * (1.0 + t.abs());
        if !(t >= first - slack && t <= last + slack) {
            return false;
        }
        if let Some(row) = self.row_at(t) {
            out.copy_from_slice(row);
            return true;
        }
        // times[i-1] < t < times[i]: the stencil i-2 .. i+1, shifted inside.
        let i = self.times.partition_point(|&s| s < t);
        let width = n.min(4);
        let lo = i.saturating_sub(2).min(n - width);
        let stencil = lo..lo + width;
        out.fill(0.0);
        for a in stencil.clone() {
            let mut weight = 1.0;
            for b in stencil.clone().filter(|&b| b != a) {
                weight *= (t - self.times[b]) / (self.times[a] - self.times[b]);
            }
            for (o, v) in out.iter_mut().zip(&self.rows[a]) {
                *o += weight * v;
            }
        }
        true
    }
}

/// The source of a reference's values.
#[derive(Clone, Debug)]
enum Source {
    /// The pendulum's closed form, its own time starting at `t0`.
    Pendulum { exact: PendulumExact, t0: f64 },
    /// Values at their own times only.
    Values(Table),
    /// Samples, interpolated.
    Trajectory(Table),
}

/// What a run is compared against (see the [module documentation](self)).
#[derive(Clone, Debug)]
pub struct Reference {
    names: Vec<String>,
    scaling: Vec<Scaling>,
    source: Source,
}

/// Why a reference cannot serve a run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum UseError {
    /// A component that is not an unknown of the model.
    #[error("`{name}` is not an unknown of the model")]
    UnknownName {
        /// The component.
        name: String,
    },
    /// A reference time outside the horizon.
    #[error("reference time {t} is outside the horizon [{t0}, {t_end}]")]
    TimeOutsideHorizon {
        /// The time.
        t: f64,
        /// Start of the horizon.
        t0: f64,
        /// End of the horizon.
        t_end: f64,
    },
    /// A check time the trajectory does not cover.
    #[error("check time {t} is outside the trajectory's samples [{first}, {last}]")]
    NotCovered {
        /// The check time.
        t: f64,
        /// First sample.
        first: f64,
        /// Last sample.
        last: f64,
    },
    /// The closed form is not defined over the whole horizon.
    #[error("the closed form is not defined at t = {t}")]
    Undefined {
        /// The time.
        t: f64,
    },
}

impl Reference {
    /// The pendulum's closed form for unknowns `x, y, v, w, lambda`
    /// ([`PendulumExact::COMPONENTS`]), absolute errors, its time `0` at
    /// the scene's start `t0`.
    pub fn pendulum(exact: PendulumExact, t0: f64) -> Reference {
        Reference {
            names: PendulumExact::COMPONENTS
                .iter()
                .map(|s| s.to_string())
                .collect(),
            scaling: vec![Scaling::Absolute; PendulumExact::COMPONENTS.len()],
            source: Source::Pendulum { exact, t0 },
        }
    }

    /// Published values at their times; `scaling` per column (a shorter
    /// list is padded with [`Scaling::Absolute`]).
    pub fn values(table: Table, scaling: Vec<Scaling>) -> Reference {
        Self::from_table(table, scaling, Source::Values)
    }

    /// A sampled solution, interpolated at the check times; `scaling` as
    /// for [`Reference::values`].
    pub fn trajectory(table: Table, scaling: Vec<Scaling>) -> Reference {
        Self::from_table(table, scaling, Source::Trajectory)
    }

    fn from_table(table: Table, mut scaling: Vec<Scaling>, wrap: fn(Table) -> Source) -> Reference {
        scaling.resize(table.names.len(), Scaling::Absolute);
        Reference {
            names: table.names.clone(),
            scaling,
            source: wrap(table),
        }
    }

    /// `exact`, `values` or `trajectory`.
    pub fn kind(&self) -> &'static str {
        match self.source {
            Source::Pendulum { .. } => "exact",
            Source::Values(_) => "values",
            Source::Trajectory(_) => "trajectory",
        }
    }

    /// The unknowns it gives, in the order of [`Reference::at`].
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// How each component's error is measured.
    pub fn scaling(&self) -> &[Scaling] {
        &self.scaling
    }

    /// The times errors are measured at, for a `values` reference (its own
    /// times); `None` for the others (the scene's check times).
    pub fn times(&self) -> Option<&[f64]> {
        match &self.source {
            Source::Values(t) => Some(&t.times),
            _ => None,
        }
    }

    /// The reference values at `t` into `out` (length `names().len()`);
    /// `false` where the reference gives none (a `values` reference between
    /// its times, a trajectory outside its samples).
    pub fn at(&self, t: f64, out: &mut [f64]) -> bool {
        match &self.source {
            Source::Pendulum { exact, t0 } => {
                out.copy_from_slice(&exact.state(t - t0));
                out.iter().all(|v| v.is_finite())
            }
            Source::Values(table) => match table.row_at(t) {
                Some(row) => {
                    out.copy_from_slice(row);
                    true
                }
                None => false,
            },
            Source::Trajectory(table) => table.interpolate(t, out),
        }
    }

    /// Check that the reference serves a run of a model with unknowns
    /// `unknowns` over `[t0, t_end]` checked at `checks`.
    pub fn check_use(
        &self,
        unknowns: &[&str],
        t0: f64,
        t_end: f64,
        checks: &[f64],
    ) -> Result<(), UseError> {
        if let Some(name) = self.names.iter().find(|n| !unknowns.contains(&n.as_str())) {
            return Err(UseError::UnknownName { name: name.clone() });
        }
        let slack = |t: f64| 1e-12 * (1.0 + t.abs());
        match &self.source {
            Source::Pendulum { .. } => {
                let mut out = vec![0.0; self.names.len()];
                if !self.at(t_end, &mut out) {
                    return Err(UseError::Undefined { t: t_end });
                }
            }
            Source::Values(table) => {
                if let Some(&t) = table
                    .times
                    .iter()
                    .find(|&&t| t < t0 - slack(t) || t > t_end + slack(t))
                {
                    return Err(UseError::TimeOutsideHorizon { t, t0, t_end });
                }
            }
            Source::Trajectory(table) => {
                let (first, last) = (table.times[0], table.times[table.times.len() - 1]);
                if let Some(&t) = checks
                    .iter()
                    .find(|&&t| t < first - slack(t) || t > last + slack(t))
                {
                    return Err(UseError::NotCovered { t, first, last });
                }
            }
        }
        Ok(())
    }
}

impl fmt::Display for Reference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.kind(), self.names.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_errors_name_the_line() {
        let e = Table::from_csv("t,x\n0,1\n1,oops\n").unwrap_err();
        assert_eq!(e.line, 3, "{e}");
        assert!(
            e.to_string().contains("column `x`: `oops` is not a number"),
            "{e}"
        );
        // Lines are counted with the comments and blank lines skipped.
        let e = Table::from_csv("# c\n\nt,x,y\n  # indented\n0,1,2\nzz,1,2\n").unwrap_err();
        assert_eq!(e.line, 6, "{e}");
        assert!(e.to_string().contains("column `t`: `zz`"), "{e}");
        // Quoted cells are CSV, not split at their commas.
        let t = Table::from_csv("t,\"x\"\n\"0\",\" 1 \"\n").unwrap();
        assert_eq!((t.names, t.rows), (vec!["x".to_string()], vec![vec![1.0]]));
        let e = Table::from_csv("time,x\n0,1\n").unwrap_err();
        assert!(e.to_string().contains("first column must be `t`"), "{e}");
        let e = Table::from_csv("t,x\n1,1\n0.5,2\n").unwrap_err();
        assert_eq!(e.line, 3, "{e}");
        let e = Table::from_csv("t,x,y\n1,1\n").unwrap_err();
        assert!(e.to_string().contains("1 values for 2 unknowns"), "{e}");
        let e = Table::from_csv("t,x,x\n1,1,2\n").unwrap_err();
        assert!(e.to_string().contains("given twice"), "{e}");
        assert!(Table::from_csv("# nothing\n").is_err());
        assert!(Table::from_csv("t,x\n").is_err());
        assert!(Table::from_csv("t,x\n0,inf\n").is_err());
    }

    #[test]
    fn interpolation_is_exact_for_cubics() {
        let f = |t: f64| 1.0 - 2.0 * t + 0.5 * t * t * t;
        let times: Vec<f64> = (0..9)
            .map(|i| 0.3 * f64::from(i) * (1.0 + 0.1 * f64::from(i)))
            .collect();
        let rows = times.iter().map(|&t| vec![f(t), -f(t)]).collect();
        let table = Table::new(vec!["a".into(), "b".into()], times.clone(), rows).unwrap();
        let mut out = [0.0; 2];
        for t in [0.0, 0.05, 0.31, 1.7, times[8] - 1e-3, times[8]] {
            assert!(table.interpolate(t, &mut out));
            assert!(
                (out[0] - f(t)).abs() < 1e-12 && (out[1] + f(t)).abs() < 1e-12,
                "{t}"
            );
        }
        assert!(!table.interpolate(-0.1, &mut out));
        assert!(!table.interpolate(times[8] + 0.1, &mut out));
        // Two samples: linear.
        let two = Table::new(vec!["a".into()], vec![0.0, 2.0], vec![vec![1.0], vec![3.0]]).unwrap();
        assert!(two.interpolate(0.5, &mut out[..1]));
        assert!((out[0] - 1.5).abs() < 1e-15);
    }

    #[test]
    fn values_are_given_only_at_their_times() {
        let table =
            Table::new(vec!["x".into()], vec![1.0, 2.0], vec![vec![3.0], vec![4.0]]).unwrap();
        let r = Reference::values(table, vec![]);
        let mut out = [0.0];
        assert!(r.at(2.0 + 1e-14, &mut out) && out[0] == 4.0);
        assert!(!r.at(1.5, &mut out));
        assert_eq!(r.scaling(), [Scaling::Absolute]);
        assert_eq!(
            r.check_use(&["x"], 0.0, 1.5, &[1.5]),
            Err(UseError::TimeOutsideHorizon {
                t: 2.0,
                t0: 0.0,
                t_end: 1.5
            })
        );
        assert_eq!(
            r.check_use(&["y"], 0.0, 3.0, &[3.0]),
            Err(UseError::UnknownName { name: "x".into() })
        );
        assert_eq!(r.check_use(&["y", "x"], 0.0, 3.0, &[3.0]), Ok(()));
    }

    #[test]
    fn relative_scaling_falls_back_to_absolute_at_zero() {
        assert_eq!(Scaling::Relative.error(1e-3, 0.0), 1e-3);
        assert_eq!(Scaling::Relative.error(-3.0, -2.0), 0.5);
        assert_eq!(Scaling::Absolute.error(-3.0, -2.0), 1.0);
        for s in SCALINGS {
            assert_eq!(Scaling::parse(s).map(Scaling::as_str), Some(s));
        }
    }
}
