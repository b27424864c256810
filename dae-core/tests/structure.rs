//! Pryce's Σ-method (`dae_core::structure`) on textbook DAEs with known
//! offsets and indices, on structurally singular systems, on random
//! patterns against brute force, and on chains of 2,000 unknowns.

use dae_core::structure::{analyse, Sigma, SigmaMatrix, Singular, Structure};
use proptest::prelude::*;

fn matrix(unknowns: usize, rows: &[&[(usize, u8)]]) -> SigmaMatrix {
    SigmaMatrix::from_rows(unknowns, rows.iter().map(|r| r.to_vec())).expect("entries in range")
}

/// The invariants every result must satisfy: d_j − c_i ≥ σ_ij, equality on
/// the transversal, a permutation, Val(Σ) = Σ d − Σ c, blocks a partition
/// in solve order.
fn check_invariants(s: &dyn Sigma, r: &Structure) {
    let (n, _) = s.size();
    let mut seen = vec![false; n];
    for &j in &r.transversal {
        assert!(!seen[j], "unknown {j} assigned twice");
        seen[j] = true;
    }
    let mut value = 0i64;
    for i in 0..n {
        for j in s.row(i) {
            let sigma = i64::from(s.sigma(i, j).unwrap());
            let gap = i64::from(r.d[j]) - i64::from(r.c[i]);
            assert!(gap >= sigma, "d_{j} − c_{i} = {gap} < σ = {sigma}");
            if r.transversal[i] == j {
                assert_eq!(gap, sigma, "not tight on the transversal at ({i}, {j})");
                value += sigma;
            }
        }
    }
    assert_eq!(r.value, value);
    assert_eq!(r.value, r.degrees_of_freedom());
    let mut block_of = vec![usize::MAX; n];
    for (b, block) in r.blocks.iter().enumerate() {
        for &i in block {
            assert_eq!(block_of[i], usize::MAX, "equation {i} in two blocks");
            block_of[i] = b;
        }
    }
    let mut owner = vec![0; n];
    for (i, &j) in r.transversal.iter().enumerate() {
        owner[j] = i;
    }
    for i in 0..n {
        for j in s.row(i) {
            assert!(
                block_of[owner[j]] <= block_of[i],
                "equation {i} needs unknown {j} of a later block"
            );
        }
    }
}

fn analysed(s: &SigmaMatrix) -> Structure {
    let r = analyse(s).expect("structurally regular");
    check_invariants(s, &r);
    r
}

#[test]
fn pendulum_first_order() {
    // unknowns x, y, u, v, λ
    let s = matrix(
        5,
        &[
            &[(0, 1), (2, 0)],         // x' = u
            &[(1, 1), (3, 0)],         // y' = v
            &[(0, 0), (2, 1), (4, 0)], // u' = −λx
            &[(1, 0), (3, 1), (4, 0)], // v' = −λy − g
            &[(0, 0), (1, 0)],         // 0 = x² + y² − 1
        ],
    );
    let r = analysed(&s);
    assert_eq!(r.c, [1, 1, 0, 0, 2]);
    assert_eq!(r.d, [2, 2, 1, 1, 0]);
    assert_eq!(r.index(), 3);
    assert_eq!(r.value, 2);
    // The system Jacobian of the pendulum: x'' and y'' in the constraint's
    // second derivative, λ in the accelerations.
    assert!(r.leading(4, 0, &s) && r.leading(4, 1, &s));
    assert!(r.leading(2, 4, &s) && r.leading(3, 4, &s));
    assert!(!r.leading(2, 0, &s));
}

#[test]
fn pendulum_second_order() {
    // unknowns x, y, λ
    let s = matrix(
        3,
        &[
            &[(0, 2), (2, 0)], // x'' = −λx
            &[(1, 2), (2, 0)], // y'' = −λy − g
            &[(0, 0), (1, 0)], // 0 = x² + y² − 1
        ],
    );
    let r = analysed(&s);
    assert_eq!(r.c, [0, 0, 2]);
    assert_eq!(r.d, [2, 2, 0]);
    assert_eq!(r.index(), 3);
    assert_eq!(r.value, 2); // the angle and its rate
}

fn cstr() -> SigmaMatrix {
    // unknowns C, T, R, TC
    matrix(
        4,
        &[
            &[(0, 1), (2, 0)],         // C' = k1(C0 − C) − R
            &[(1, 1), (2, 0), (3, 0)], // T' = k1(T0 − T) + k2 R − k3(T − TC)
            &[(0, 0), (1, 0), (2, 0)], // 0 = R − k exp(−k4/T) C
            &[(0, 0)],                 // 0 = C − u(t)
        ],
    )
}

#[test]
fn cstr_with_prescribed_output() {
    // By hand: only e3 can take C, so e0 takes R, e2 takes T, e1 takes TC;
    // Val = 0. From c = 0: d = (1, 1, 0, 0), c = (1, 0, 0, 1); then
    // d = (2, 1, 1, 0), c = (1, 0, 1, 2); then unchanged.
    let s = cstr();
    let r = analysed(&s);
    assert_eq!(r.transversal, [2, 3, 1, 0]);
    assert_eq!(r.c, [1, 0, 1, 2]);
    assert_eq!(r.d, [2, 1, 1, 0]);
    assert_eq!(r.index(), 3);
    assert_eq!(r.value, 0);
    // C from its equation, then R, then T, then TC: one equation a block.
    assert_eq!(r.blocks, [vec![3], vec![0], vec![2], vec![1]]);
}

#[test]
fn linear_index_three_chain() {
    // x1' = x2, x2' = x3, 0 = x1 − sin t
    let s = matrix(3, &[&[(0, 1), (1, 0)], &[(1, 1), (2, 0)], &[(0, 0)]]);
    let r = analysed(&s);
    assert_eq!(r.c, [1, 0, 2]);
    assert_eq!(r.d, [2, 1, 0]);
    assert_eq!(r.index(), 3);
    assert_eq!(r.value, 0);
}

#[test]
fn gear_hsu_petzold_passes_with_a_singular_system_jacobian() {
    // 0 = y1 + ηt y2 − f;  y1' + ηt y2' + (1 + η) y2 = g. Structurally index
    // 1, but the system Jacobian [[1, ηt], [1, ηt]] is singular: the known
    // failure of the Σ-method (its true index is 2).
    let s = matrix(2, &[&[(0, 0), (1, 0)], &[(0, 1), (1, 1)]]);
    let r = analysed(&s);
    assert_eq!(r.c, [1, 0]);
    assert_eq!(r.d, [1, 1]);
    assert_eq!(r.index(), 1);
    assert_eq!(r.value, 1);
    for i in 0..2 {
        for j in 0..2 {
            assert!(r.leading(i, j, &s), "({i}, {j}) should be leading");
        }
    }
}

/// Andrews' squeezer in the IVP Test Set's index-3 form: q' = v, v' = a,
/// M(q) a − f(q, v) + G(q)ᵀ λ = 0, g(q) = 0, with the sparsity of the Test
/// Set's code (q = β, Θ, γ, Φ, δ, Ω, ε).
fn squeezer() -> SigmaMatrix {
    let (q, v, a, l) = (0, 7, 14, 21);
    let mut s = SigmaMatrix::new(27, 27);
    let mut set = |i: usize, j: usize, o: u8| s.set(i, j, o).unwrap();
    for k in 0..7 {
        set(k, q + k, 1); // q_k' = v_k
        set(k, v + k, 0);
        set(7 + k, v + k, 1); // v_k' = a_k
        set(7 + k, a + k, 0);
    }
    // Row k of M a − f + Gᵀλ (0-based k): the accelerations of M's row, the
    // positions in M's row, f_k and column k of G, the velocities in f_k,
    // the multipliers of the constraints involving q_k.
    let mass: [&[usize]; 7] = [&[0, 1], &[0, 1], &[2], &[3, 4], &[3, 4], &[5, 6], &[5, 6]];
    let positions: [&[usize]; 7] = [&[0, 1], &[0, 1], &[2], &[3, 4], &[3, 4], &[5, 6], &[5, 6]];
    let velocities: [&[usize]; 7] = [&[0, 1], &[0], &[], &[4], &[3, 4], &[6], &[5, 6]];
    let multipliers: [&[usize]; 7] = [
        &[0, 1, 2, 3, 4, 5],
        &[0, 1, 2, 3, 4, 5],
        &[0, 1],
        &[2, 3],
        &[2, 3],
        &[4, 5],
        &[4, 5],
    ];
    for k in 0..7 {
        let e = 14 + k;
        mass[k].iter().for_each(|&m| set(e, a + m, 0));
        positions[k].iter().for_each(|&m| set(e, q + m, 0));
        velocities[k].iter().for_each(|&m| set(e, v + m, 0));
        multipliers[k].iter().for_each(|&m| set(e, l + m, 0));
    }
    // g_1, g_2: β, Θ, γ; g_3, g_4: β, Θ, Φ, δ; g_5, g_6: β, Θ, Ω, ε.
    let constraints: [&[usize]; 6] = [
        &[0, 1, 2],
        &[0, 1, 2],
        &[0, 1, 3, 4],
        &[0, 1, 3, 4],
        &[0, 1, 5, 6],
        &[0, 1, 5, 6],
    ];
    for (m, g) in constraints.iter().enumerate() {
        g.iter().for_each(|&k| set(21 + m, q + k, 0));
    }
    s
}

#[test]
fn andrews_squeezer_index_three() {
    let s = squeezer();
    let r = analysed(&s);
    let mut c = vec![1; 7];
    c.extend([0; 14]);
    c.extend([2; 6]);
    let mut d = vec![2; 7];
    d.extend([1; 7]);
    d.extend([0; 13]);
    assert_eq!(r.c, c);
    assert_eq!(r.d, d);
    assert_eq!(r.index(), 3);
    // One position and its velocity are free: 7 positions, 6 constraints.
    assert_eq!(r.value, 2);
}

#[test]
fn empty_system() {
    let r = analysed(&SigmaMatrix::new(0, 0));
    assert_eq!(r.index(), 0);
    assert!(r.blocks.is_empty() && r.transversal.is_empty());
}

#[test]
fn not_square() {
    assert_eq!(
        analyse(&SigmaMatrix::new(2, 3)),
        Err(Singular::NotSquare {
            equations: 2,
            unknowns: 3
        })
    );
}

#[test]
fn a_missing_unknown() {
    // x' = y, y' = −x, 0 = x + y − 1; z occurs nowhere.
    let s = matrix(
        3,
        &[&[(0, 1), (1, 0)], &[(0, 0), (1, 1)], &[(0, 0), (1, 0)]],
    );
    let e = analyse(&s).unwrap_err();
    assert_eq!(
        e.to_string(),
        "structurally singular: equations 0, 1, 2 compete for unknowns 0, 1 \
         (1 too many equations); nothing determines unknown 2 (no equation involves it)"
    );
    let Singular::NoTransversal {
        equations,
        unknowns,
        unmatched_equations,
        unmatched_unknowns,
        underdetermined_equations,
        underdetermined_unknowns,
    } = e
    else {
        panic!("expected NoTransversal, got {e:?}");
    };
    assert_eq!(equations, [0, 1, 2]);
    assert_eq!(unknowns, [0, 1]);
    assert_eq!(unmatched_equations.len(), 1);
    assert!(equations.contains(&unmatched_equations[0]));
    assert_eq!(unmatched_unknowns, [2]);
    assert!(underdetermined_equations.is_empty());
    assert_eq!(underdetermined_unknowns, [2]);
}

#[test]
fn two_equations_for_one_unknown() {
    // The CSTR written without TC in the energy balance and with the rate
    // given twice: 0 = R − k exp(−k4/T) C and 0 = R − r(t). Equations 2 and
    // 3 compete for R; T' = … then has T alone, and TC is left to nothing.
    let s = matrix(
        4,
        &[
            &[(0, 1)],         // C' = k1(C0 − C)
            &[(1, 1), (2, 0)], // T' = k1(T0 − T) + k2 R
            &[(2, 0)],         // 0 = R − r1(t)
            &[(2, 0)],         // 0 = R − r2(t)
        ],
    );
    let e = analyse(&s).unwrap_err();
    let Singular::NoTransversal {
        equations,
        unknowns,
        unmatched_equations,
        unmatched_unknowns,
        underdetermined_equations,
        underdetermined_unknowns,
    } = e.clone()
    else {
        panic!("expected NoTransversal, got {e:?}");
    };
    assert_eq!(equations, [2, 3]);
    assert_eq!(unknowns, [2]);
    assert_eq!(unmatched_equations.len(), 1);
    assert_eq!(unmatched_unknowns, [3]);
    assert!(underdetermined_equations.is_empty());
    assert_eq!(underdetermined_unknowns, [3]);
    assert_eq!(
        e.to_string(),
        "structurally singular: equations 2, 3 compete for unknown 2 \
         (1 too many equations); nothing determines unknown 3 (no equation involves it)"
    );
}

#[test]
fn under_determined_part_with_its_equations() {
    // e0, e1 only in x; e2 in y and z.
    let s = matrix(3, &[&[(0, 0)], &[(0, 1)], &[(1, 0), (2, 1)]]);
    let e = analyse(&s).unwrap_err();
    assert_eq!(
        e.to_string(),
        "structurally singular: equations 0, 1 compete for unknown 0 (1 too many equations); \
         nothing determines unknowns 1, 2 (only equation 2 for 2 unknowns)"
    );
    match e {
        Singular::NoTransversal {
            underdetermined_equations,
            underdetermined_unknowns,
            ..
        } => {
            assert_eq!(underdetermined_equations, [2]);
            assert_eq!(underdetermined_unknowns, [1, 2]);
        }
        other => panic!("expected NoTransversal, got {other:?}"),
    }
}

/// A [`Sigma`] that reports whatever it is told, to check the analysis
/// refuses inconsistent input with a typed error.
struct Raw(Vec<Vec<(usize, Option<u8>)>>);

impl Sigma for Raw {
    fn size(&self) -> (usize, usize) {
        (self.0.len(), self.0.len())
    }
    fn sigma(&self, i: usize, j: usize) -> Option<u8> {
        self.0[i].iter().find(|e| e.0 == j).and_then(|e| e.1)
    }
    fn row(&self, i: usize) -> Vec<usize> {
        self.0[i].iter().map(|e| e.0).collect()
    }
}

#[test]
fn inconsistent_sigma_is_a_typed_error() {
    let out = Raw(vec![vec![(0, Some(0)), (2, Some(0))], vec![(1, Some(0))]]);
    assert_eq!(
        analyse(&out),
        Err(Singular::UnknownOutOfRange {
            equation: 0,
            unknown: 2,
            unknowns: 2
        })
    );
    let descending = Raw(vec![vec![(0, Some(0))], vec![(1, Some(0)), (0, Some(1))]]);
    assert_eq!(
        analyse(&descending),
        Err(Singular::RowNotAscending {
            equation: 1,
            unknown: 0,
            previous: 1
        })
    );
    let repeated = Raw(vec![vec![(0, Some(0)), (0, Some(0))], vec![(1, Some(0))]]);
    assert!(matches!(
        analyse(&repeated),
        Err(Singular::RowNotAscending { .. })
    ));
    let missing = Raw(vec![vec![(0, Some(0))], vec![(1, None)]]);
    assert_eq!(
        analyse(&missing),
        Err(Singular::MissingSigma {
            equation: 1,
            unknown: 1
        })
    );
}

/// A planar chain of `links` pendula (x, y, u, v, λ per link), each link's
/// rod attached to the previous link's bob: five unknowns and equations a
/// link, about three entries a row.
fn mechanical_chain(links: usize) -> SigmaMatrix {
    let n = 5 * links;
    let mut s = SigmaMatrix::new(n, n);
    let mut set = |i: usize, j: usize, o: u8| s.set(i, j, o).unwrap();
    for k in 0..links {
        let (x, y, u, v, l) = (5 * k, 5 * k + 1, 5 * k + 2, 5 * k + 3, 5 * k + 4);
        set(x, x, 1); // x' = u
        set(x, u, 0);
        set(y, y, 1); // y' = v
        set(y, v, 0);
        // u' = (−λ_k (x_k − x_{k−1}) + λ_{k+1} (x_{k+1} − x_k)) / m
        for (row, pos, vel) in [(u, x, u), (v, y, v)] {
            set(row, vel, 1);
            set(row, pos, 0);
            set(row, l, 0);
            if k > 0 {
                set(row, pos - 5, 0);
            }
            if k + 1 < links {
                set(row, pos + 5, 0);
                set(row, l + 5, 0);
            }
        }
        // 0 = (x_k − x_{k−1})² + (y_k − y_{k−1})² − L²
        set(l, x, 0);
        set(l, y, 0);
        if k > 0 {
            set(l, x - 5, 0);
            set(l, y - 5, 0);
        }
    }
    s
}

#[test]
fn chain_of_400_links() {
    let links = 400;
    let s = mechanical_chain(links);
    assert_eq!(s.size(), (2000, 2000));
    let r = analysed(&s);
    for k in 0..links {
        assert_eq!(&r.c[5 * k..5 * k + 5], [1, 1, 0, 0, 2], "link {k}");
        assert_eq!(&r.d[5 * k..5 * k + 5], [2, 2, 1, 1, 0], "link {k}");
    }
    assert_eq!(r.index(), 3);
    assert_eq!(r.value, 2 * links as i64);
}

#[test]
fn linear_chain_of_index_2000() {
    // x_k' = x_{k+1} (k < n), 0 = x_1 − sin t: the constraint is
    // differentiated n − 1 times, ν = n; the offset iteration needs n sweeps.
    let n = 2000;
    let mut rows: Vec<Vec<(usize, u8)>> = (0..n - 1).map(|k| vec![(k, 1), (k + 1, 0)]).collect();
    rows.push(vec![(0, 0)]);
    let s = SigmaMatrix::from_rows(n, rows).unwrap();
    let r = analysed(&s);
    assert_eq!(r.index(), n as u32);
    assert_eq!(r.c[n - 1], (n - 1) as u32);
    assert_eq!(r.d[0], (n - 1) as u32);
    assert_eq!(r.c[0], (n - 2) as u32);
    assert_eq!(r.d[n - 1], 0);
    assert_eq!(r.value, 0);
}

/// Random square patterns of size 1..=max_n with σ ≤ 3, containing the
/// entries of a random permutation (so a transversal exists) when `full`.
fn patterns(max_n: usize, full: bool) -> impl Strategy<Value = SigmaMatrix> {
    (1..=max_n)
        .prop_flat_map(move |n| {
            (
                Just(n),
                proptest::collection::vec(proptest::option::weighted(0.35, 0u8..=3), n * n),
                Just((0..n).collect::<Vec<usize>>()).prop_shuffle(),
                proptest::collection::vec(0u8..=3, n),
            )
        })
        .prop_map(move |(n, dense, perm, diag)| {
            let mut s = SigmaMatrix::new(n, n);
            for i in 0..n {
                for j in 0..n {
                    if let Some(o) = dense[i * n + j] {
                        s.set(i, j, o).unwrap();
                    }
                }
                if full {
                    s.set(i, perm[i], diag[i]).unwrap();
                }
            }
            s
        })
}

/// The highest Σσ over all transversals, or None if there is none.
fn brute_force_value(s: &SigmaMatrix) -> Option<i64> {
    let (n, _) = s.size();
    let mut perm: Vec<usize> = (0..n).collect();
    let mut best = None;
    // Heap's algorithm, iterative.
    let mut count = vec![0usize; n];
    let mut visit = |p: &[usize]| {
        let v: Option<i64> = (0..n).map(|i| s.sigma(i, p[i]).map(i64::from)).sum();
        if let Some(v) = v {
            best = Some(best.map_or(v, |b: i64| b.max(v)));
        }
    };
    visit(&perm);
    let mut i = 0;
    while i < n {
        if count[i] < i {
            if i % 2 == 0 {
                perm.swap(0, i);
            } else {
                perm.swap(count[i], i);
            }
            visit(&perm);
            count[i] += 1;
            i = 0;
        } else {
            count[i] = 0;
            i += 1;
        }
    }
    best
}

/// Whether `c` are valid offsets: with d_j = max_i σ_ij + c_i, equality
/// d_j − c_i = σ_ij on the transversal `t` (a highest-value one).
fn valid_offsets(s: &SigmaMatrix, t: &[usize], c: &[i64]) -> bool {
    let (n, _) = s.size();
    let mut d = vec![i64::MIN; n];
    for (i, &ci) in c.iter().enumerate() {
        for j in s.row(i) {
            d[j] = d[j].max(i64::from(s.sigma(i, j).unwrap()) + ci);
        }
    }
    (0..n).all(|i| d[t[i]] - c[i] == i64::from(s.sigma(i, t[i]).unwrap()))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn highest_value_and_tight_offsets(s in patterns(6, true)) {
        let r = analyse(&s).expect("a transversal exists");
        check_invariants(&s, &r);
        prop_assert_eq!(Some(r.value), brute_force_value(&s));
    }

    #[test]
    fn offsets_are_the_smallest(s in patterns(4, true)) {
        let r = analyse(&s).expect("a transversal exists");
        let (n, _) = s.size();
        let c: Vec<i64> = r.c.iter().map(|&x| i64::from(x)).collect();
        prop_assert!(valid_offsets(&s, &r.transversal, &c));
        // Every valid c in the box [0, max c + 1]^n is ≥ the one found.
        let top = c.iter().copied().max().unwrap_or(0) + 1;
        let mut trial = vec![0i64; n];
        loop {
            if valid_offsets(&s, &r.transversal, &trial) {
                for i in 0..n {
                    prop_assert!(trial[i] >= c[i], "valid {:?} below {:?}", trial, c);
                }
            }
            let mut k = 0;
            while k < n && trial[k] == top {
                trial[k] = 0;
                k += 1;
            }
            if k == n {
                break;
            }
            trial[k] += 1;
        }
    }

    #[test]
    fn singular_exactly_when_no_transversal(s in patterns(6, false)) {
        let (n, _) = s.size();
        match (analyse(&s), brute_force_value(&s)) {
            (Ok(r), Some(v)) => {
                check_invariants(&s, &r);
                prop_assert_eq!(r.value, v);
            }
            (Err(Singular::NoTransversal {
                equations,
                unknowns,
                unmatched_equations,
                unmatched_unknowns,
                underdetermined_equations,
                underdetermined_unknowns,
            }), None) => {
                // Both parts are closed: the over-determined equations only
                // involve its unknowns, the under-determined unknowns occur
                // only in its equations; each part is deficient by the
                // number of free equations or unknowns.
                for &i in &equations {
                    for j in s.row(i) {
                        prop_assert!(unknowns.contains(&j));
                    }
                }
                for i in 0..n {
                    if s.row(i).iter().any(|j| underdetermined_unknowns.contains(j)) {
                        prop_assert!(underdetermined_equations.contains(&i));
                    }
                }
                prop_assert_eq!(equations.len() - unknowns.len(), unmatched_equations.len());
                prop_assert_eq!(
                    underdetermined_unknowns.len() - underdetermined_equations.len(),
                    unmatched_unknowns.len()
                );
                prop_assert_eq!(unmatched_equations.len(), unmatched_unknowns.len());
                prop_assert!(!unmatched_equations.is_empty());
            }
            (other, brute) => prop_assert!(false, "analyse gave {:?}, brute force {:?}", other, brute),
        }
    }
}
