//! Names a user may mistype, and the one rule that suggests the intended
//! one: for the model language's functions, a scene's solvers,
//! formulations, unknowns and parameters, and a solution's unknowns.

/// The known name closest to `given`, if one is close enough to be a typo:
/// at most one edit (insertion, deletion, substitution, or transposition
/// of neighbours: the optimal-string-alignment distance) for names of up
/// to four characters, two for longer ones, never as many as half of
/// `given`. Ties go to the first in `known`. Case is ignored.
///
/// ```
/// use dae_core::names::did_you_mean;
///
/// let solvers = ["radau5", "bdf", "odradau", "gauss"];
/// assert_eq!(did_you_mean("radua5", &solvers), Some("radau5"));
/// assert_eq!(did_you_mean("BDF", &solvers), Some("bdf"));
/// assert_eq!(did_you_mean("euler", &solvers), None);
/// assert_eq!(did_you_mean("ggl", &["ggl1", "rcd1"]), Some("ggl1"));
/// ```
pub fn did_you_mean<'a, S: AsRef<str>>(given: &str, known: &'a [S]) -> Option<&'a str> {
    let given = given.to_lowercase();
    let len = given.chars().count();
    let limit = if len <= 4 { 1 } else { 2 };
    let mut best: Option<(usize, &'a str)> = None;
    for k in known {
        let k = k.as_ref();
        let d = strsim::osa_distance(&given, &k.to_lowercase());
        if d <= limit && 2 * d < len.max(2) && !matches!(best, Some((b, _)) if b <= d) {
            best = Some((d, k));
        }
    }
    best.map(|(_, k)| k)
}
