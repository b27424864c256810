/*
 * SUNDIALS IDA on the N-link planar pendulum chain of scripts/chain.py, in
 * the index-1 form that `dae derive` calls rcd0: the dynamics rows with the
 * constraints replaced by their second time derivatives (acceleration
 * level). The benchmark partner of `dae run ... --solver bdf --formulation
 * rcd0` (BENCHMARKS.md §16, issue 24 done-when 2); built and run by
 * scripts/ida_chain.sh. Not part of the Rust workspace and not a test.
 *
 * The model (scripts/chain.py, parameters m = l = 1, g = 9.81): point
 * masses p_i = (x_i, y_i), velocities q_i = (u_i, v_i), multipliers la_i,
 * i = 1..N; with p_0 = q_0 = 0, d_i = p_i - p_{i-1}, w_i = q_i - q_{i-1}:
 *
 *   x_i' = u_i,  y_i' = v_i,
 *   m q_i' = -2 la_i d_i + 2 la_{i+1} d_{i+1} - (0, m g)   (no la_{N+1}),
 *   0 = |d_i|^2 - l^2                                       (index 3).
 *
 * rcd0 replaces the last rows by 0 = d^2/dt^2 (|d_i|^2 - l^2) with the
 * accelerations substituted from the dynamics rows, a_i = q_i', a_0 = 0:
 *
 *   G_i = 2 |w_i|^2 + 2 d_i . (a_i - a_{i-1})
 *       = 2 |w_i|^2 + (4 la_{i-1} d_{i-1}.d_i - K_i la_i |d_i|^2
 *                      + 4 la_{i+1} d_{i+1}.d_i) / m - [i = 1] 2 g y_1,
 *
 * K_1 = 4, K_i = 8 for i >= 2 (gravity cancels in a_i - a_{i-1} for
 * i >= 2; terms with la_0 or la_{N+1} are absent). This is, expanded,
 * exactly the text `dae derive` prints for rcd0 of the generated chain.
 *
 * IDA's residual is F(t, y, y') = E y' - f(y) row by row as dae's rows are
 * written (`der(x) = u` gives x' - u, `m der(u) = ...` gives m u' - ...,
 * `0 = G` gives G). Unknowns and rows are interleaved per link,
 * (x_i, y_i, u_i, v_i, la_i) at 5(i-1)..5(i-1)+4, so the iteration matrix
 * dF/dy + cj dF/dy' is block tridiagonal with 5x5 blocks (at most 19
 * non-zeros in a row); KLU orders it itself.
 *
 * Usage: ida_chain N [klu|dense] [tol] [t_end] [check]
 *   Integrates from the chain stretched out horizontally at rest
 *   (x_i = i, y_i = 0, u = v = 0) with rtol = atol = tol (default 1e-6, as
 *   `dae run --tol 1e-6`) over [0, t_end] (default 1), stopping exactly at
 *   t_end (IDASetStopTime), and prints one JSON object: the work counters,
 *   `cpu_s` (CPU time of this thread, CLOCK_THREAD_CPUTIME_ID, from
 *   IDACreate to the return of IDASolve at t_end: set-up, the KLU symbolic
 *   analysis and the integration) and the final positions. `check` instead
 *   compares the analytic Jacobian with central differences of the
 *   residual at a perturbed state and exits 1 if they disagree.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#define M_MASS 1.0
#define L_LEN 1.0
#define G_ACC 9.81

/* Index of component k (0 x, 1 y, 2 u, 3 v, 4 la) of link i (1-based). */
#define IX(i, k) (5 * ((i) - 1) + (k))

/* How the Jacobian's entries are delivered: recorded as a pattern, added
 * into a compressed column matrix through the pattern's map, or added into
 * a dense matrix. */
enum mode { PATTERN, SPARSE, DENSE };

typedef struct {
  int n;              /* links */
  enum mode mode;
  long k;             /* entries emitted so far in this evaluation */
  /* PATTERN: the emitted (row, col), in emission order. */
  sunindextype *prow, *pcol;
  long cap;
  /* SPARSE: map[k] = position of entry k in the CSC arrays. */
  sunindextype *map;
  sunindextype nnz;
  sunindextype *colptr, *rowind;
  double *data;       /* SPARSE: the CSC values */
  SUNMatrix dense;    /* DENSE */
} Jac;

static void put(Jac *J, sunindextype r, sunindextype c, double v) {
  switch (J->mode) {
  case PATTERN:
    if (J->k == J->cap) {
      J->cap = J->cap ? 2 * J->cap : 1024;
      J->prow = realloc(J->prow, J->cap * sizeof *J->prow);
      J->pcol = realloc(J->pcol, J->cap * sizeof *J->pcol);
      if (!J->prow || !J->pcol) {
        fprintf(stderr, "ida_chain: out of memory\n");
        exit(2);
      }
    }
    J->prow[J->k] = r;
    J->pcol[J->k] = c;
    break;
  case SPARSE:
    J->data[J->map[J->k]] += v;
    break;
  case DENSE:
    SM_ELEMENT_D(J->dense, r, c) += v;
    break;
  }
  J->k++;
}

/* d_i (component c: 0 x, 1 y) and w_i; zero for i = 0 or i > n. */
static double dd(const double *y, int n, int i, int c) {
  if (i < 1 || i > n) return 0.0;
  return y[IX(i, c)] - (i > 1 ? y[IX(i - 1, c)] : 0.0);
}
static double ww(const double *y, int n, int i, int c) {
  if (i < 1 || i > n) return 0.0;
  return y[IX(i, 2 + c)] - (i > 1 ? y[IX(i - 1, 2 + c)] : 0.0);
}
static double la(const double *y, int n, int i) {
  return (i < 1 || i > n) ? 0.0 : y[IX(i, 4)];
}

/* The residual F(t, y, y') into r. */
static void residual(int n, const double *y, const double *yp, double *r) {
  const double m = M_MASS, g = G_ACC;
  for (int i = 1; i <= n; i++) {
    r[IX(i, 0)] = yp[IX(i, 0)] - y[IX(i, 2)];
    r[IX(i, 1)] = yp[IX(i, 1)] - y[IX(i, 3)];
    for (int c = 0; c < 2; c++)
      r[IX(i, 2 + c)] = m * yp[IX(i, 2 + c)] + 2.0 * la(y, n, i) * dd(y, n, i, c) -
                        2.0 * la(y, n, i + 1) * dd(y, n, i + 1, c);
    r[IX(i, 3)] += m * g;
    double w2 = 0, dm = 0, d2 = 0, dp = 0;
    for (int c = 0; c < 2; c++) {
      double di = dd(y, n, i, c);
      w2 += ww(y, n, i, c) * ww(y, n, i, c);
      dm += dd(y, n, i - 1, c) * di;
      d2 += di * di;
      dp += dd(y, n, i + 1, c) * di;
    }
    double kk = i == 1 ? 4.0 : 8.0;
    r[IX(i, 4)] = 2.0 * w2 +
                  (4.0 * la(y, n, i - 1) * dm - kk * la(y, n, i) * d2 +
                   4.0 * la(y, n, i + 1) * dp) / m -
                  (i == 1 ? 2.0 * g * y[IX(1, 1)] : 0.0);
  }
}

/* dF/dy + cj dF/dy', entry by entry (the same entries in the same order at
 * every call; repeated (row, col) pairs add up). */
static void jacobian(Jac *J, const double *y, double cj) {
  const int n = J->n;
  const double m = M_MASS, g = G_ACC;
  J->k = 0;
  for (int i = 1; i <= n; i++) {
    for (int c = 0; c < 2; c++) {
      /* x_i' - u_i (c = 0), y_i' - v_i (c = 1) */
      put(J, IX(i, c), IX(i, c), cj);
      put(J, IX(i, c), IX(i, 2 + c), -1.0);
    }
    for (int c = 0; c < 2; c++) {
      /* m q_i' + 2 la_i d_i - 2 la_{i+1} d_{i+1} (+ m g) */
      sunindextype r = IX(i, 2 + c);
      put(J, r, r, cj * m);
      put(J, r, IX(i, c), 2.0 * la(y, n, i) + 2.0 * la(y, n, i + 1));
      put(J, r, IX(i, 4), 2.0 * dd(y, n, i, c));
      if (i > 1) put(J, r, IX(i - 1, c), -2.0 * la(y, n, i));
      if (i < n) {
        put(J, r, IX(i + 1, c), -2.0 * la(y, n, i + 1));
        put(J, r, IX(i + 1, 4), -2.0 * dd(y, n, i + 1, c));
      }
    }
    /* G_i */
    sunindextype r = IX(i, 4);
    double kk = i == 1 ? 4.0 : 8.0;
    double dm = 0, d2 = 0, dp = 0;
    for (int c = 0; c < 2; c++) {
      double di = dd(y, n, i, c);
      dm += dd(y, n, i - 1, c) * di;
      d2 += di * di;
      dp += dd(y, n, i + 1, c) * di;
    }
    put(J, r, IX(i, 4), -kk * d2 / m);
    if (i > 1) put(J, r, IX(i - 1, 4), 4.0 * dm / m);
    if (i < n) put(J, r, IX(i + 1, 4), 4.0 * dp / m);
    for (int c = 0; c < 2; c++) {
      double wi = ww(y, n, i, c), di = dd(y, n, i, c);
      put(J, r, IX(i, 2 + c), 4.0 * wi);
      if (i > 1) put(J, r, IX(i - 1, 2 + c), -4.0 * wi);
      /* gradients of the bracket / m by d_{i-1}, d_i, d_{i+1} */
      double gd = (4.0 * la(y, n, i - 1) * dd(y, n, i - 1, c) - 2.0 * kk * la(y, n, i) * di +
                   4.0 * la(y, n, i + 1) * dd(y, n, i + 1, c)) / m;
      double gdm = 4.0 * la(y, n, i - 1) * di / m;
      double gdp = 4.0 * la(y, n, i + 1) * di / m;
      double own = gd - gdp + (i == 1 && c == 1 ? -2.0 * g : 0.0);
      put(J, r, IX(i, c), own);
      if (i > 1) put(J, r, IX(i - 1, c), -gd + gdm);
      if (i > 2) put(J, r, IX(i - 2, c), -gdm);
      if (i < n) put(J, r, IX(i + 1, c), gdp);
    }
  }
}

static const sunindextype *cmp_r, *cmp_c;
static int cmp_entry(const void *a, const void *b) {
  long i = *(const long *)a, j = *(const long *)b;
  if (cmp_c[i] != cmp_c[j]) return cmp_c[i] < cmp_c[j] ? -1 : 1;
  if (cmp_r[i] != cmp_r[j]) return cmp_r[i] < cmp_r[j] ? -1 : 1;
  return i < j ? -1 : (i > j);
}

/* Records the pattern once and builds the CSC structure and the map. */
static void build_pattern(Jac *J, sunindextype neq) {
  double *y = calloc(neq, sizeof *y);
  J->mode = PATTERN;
  jacobian(J, y, 1.0);
  free(y);
  long ne = J->k;
  long *order = malloc(ne * sizeof *order);
  for (long k = 0; k < ne; k++) order[k] = k;
  cmp_r = J->prow;
  cmp_c = J->pcol;
  qsort(order, ne, sizeof *order, cmp_entry);
  J->map = malloc(ne * sizeof *J->map);
  J->rowind = malloc(ne * sizeof *J->rowind);
  J->colptr = calloc(neq + 1, sizeof *J->colptr);
  sunindextype nnz = 0;
  for (long s = 0; s < ne; s++) {
    long k = order[s];
    if (s == 0 || J->prow[k] != J->prow[order[s - 1]] || J->pcol[k] != J->pcol[order[s - 1]]) {
      J->rowind[nnz] = J->prow[k];
      J->colptr[J->pcol[k] + 1]++;
      nnz++;
    }
    J->map[k] = nnz - 1;
  }
  for (sunindextype c = 0; c < neq; c++) J->colptr[c + 1] += J->colptr[c];
  J->nnz = nnz;
  free(order);
}

static int res_fn(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *user) {
  (void)t;
  Jac *J = user;
  residual(J->n, N_VGetArrayPointer(yy), N_VGetArrayPointer(yp), N_VGetArrayPointer(rr));
  return 0;
}

static int jac_fn(realtype t, realtype cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix A,
                  void *user, N_Vector t1, N_Vector t2, N_Vector t3) {
  (void)t; (void)yp; (void)rr; (void)t1; (void)t2; (void)t3;
  Jac *J = user;
  if (J->mode == SPARSE) {
    /* IDA zeroes the matrix, structure included, before each call. */
    sunindextype *cp = SM_INDEXPTRS_S(A), *ri = SM_INDEXVALS_S(A);
    memcpy(cp, J->colptr, (SM_COLUMNS_S(A) + 1) * sizeof *cp);
    memcpy(ri, J->rowind, J->nnz * sizeof *ri);
    J->data = SM_DATA_S(A);
    memset(J->data, 0, J->nnz * sizeof *J->data);
  } else {
    J->dense = A;
    SUNMatZero(A);
  }
  jacobian(J, N_VGetArrayPointer(yy), cj);
  return 0;
}

/* Consistent initial values for given positions and velocities: the
 * multipliers from G(y) = 0, linear and tridiagonal in them (Thomas
 * algorithm), then y' from the explicit rows (la' = 0, as dae's
 * minimum-norm initial derivative gives at a state where the constraint
 * chain's next derivative vanishes; F does not depend on it). */
static void consistent(int n, double *y, double *yp) {
  const double m = M_MASS, g = G_ACC;
  double *a = calloc(n + 2, sizeof *a), *b = calloc(n + 2, sizeof *b), *c = calloc(n + 2, sizeof *c),
         *d = calloc(n + 2, sizeof *d);
  for (int i = 1; i <= n; i++) {
    double w2 = 0, dm = 0, d2 = 0, dp = 0;
    for (int k = 0; k < 2; k++) {
      double di = dd(y, n, i, k);
      w2 += ww(y, n, i, k) * ww(y, n, i, k);
      dm += dd(y, n, i - 1, k) * di;
      d2 += di * di;
      dp += dd(y, n, i + 1, k) * di;
    }
    a[i] = 4.0 * dm / m;
    b[i] = -(i == 1 ? 4.0 : 8.0) * d2 / m;
    c[i] = 4.0 * dp / m;
    d[i] = -(2.0 * w2 - (i == 1 ? 2.0 * g * y[IX(1, 1)] : 0.0));
  }
  for (int i = 2; i <= n; i++) {
    double f = a[i] / b[i - 1];
    b[i] -= f * c[i - 1];
    d[i] -= f * d[i - 1];
  }
  for (int i = n; i >= 1; i--) y[IX(i, 4)] = (d[i] - (i < n ? c[i] * y[IX(i + 1, 4)] : 0.0)) / b[i];
  free(a); free(b); free(c); free(d);
  for (int i = 1; i <= n; i++) {
    yp[IX(i, 0)] = y[IX(i, 2)];
    yp[IX(i, 1)] = y[IX(i, 3)];
    for (int k = 0; k < 2; k++)
      yp[IX(i, 2 + k)] = (-2.0 * la(y, n, i) * dd(y, n, i, k) + 2.0 * la(y, n, i + 1) * dd(y, n, i + 1, k)) / m;
    yp[IX(i, 3)] -= g;
    yp[IX(i, 4)] = 0.0;
  }
}

static double thread_cpu(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Analytic against central differences at a perturbed state. */
static int check(Jac *J, sunindextype neq) {
  double *y = malloc(neq * sizeof *y), *yp = malloc(neq * sizeof *yp);
  double *r1 = malloc(neq * sizeof *r1), *r2 = malloc(neq * sizeof *r2);
  const double cj = 3.7;
  srand(7);
  for (sunindextype k = 0; k < neq; k++) {
    y[k] = (k % 5 == 0 ? 1.0 : 0.0) + (double)rand() / RAND_MAX - 0.5;
    yp[k] = (double)rand() / RAND_MAX - 0.5;
  }
  SUNContext ctx;
  SUNContext_Create(NULL, &ctx);
  SUNMatrix D = SUNDenseMatrix(neq, neq, ctx);
  J->mode = DENSE;
  J->dense = D;
  SUNMatZero(D);
  jacobian(J, y, cj);
  double worst = 0;
  for (sunindextype c = 0; c < neq; c++) {
    double h = 1e-6, sy = y[c], sp = yp[c];
    y[c] = sy + h; yp[c] = sp + cj * h;
    residual(J->n, y, yp, r1);
    y[c] = sy - h; yp[c] = sp - cj * h;
    residual(J->n, y, yp, r2);
    y[c] = sy; yp[c] = sp;
    for (sunindextype r = 0; r < neq; r++) {
      double fd = (r1[r] - r2[r]) / (2 * h), an = SM_ELEMENT_D(D, r, c);
      double e = fabs(fd - an) / (1.0 + fabs(fd));
      if (e > worst) worst = e;
      if (e > 1e-6) printf("row %ld col %ld: analytic %.10g, differences %.10g\n", (long)r, (long)c, an, fd);
    }
  }
  printf("{\"n\": %d, \"jacobian_check_worst_relative\": %.3e}\n", J->n, worst);
  SUNMatDestroy(D);
  SUNContext_Free(&ctx);
  free(y); free(yp); free(r1); free(r2);
  return worst > 1e-6;
}

static void fail(const char *what, long flag) {
  fprintf(stderr, "ida_chain: %s failed (%ld)\n", what, flag);
  exit(2);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: ida_chain N [klu|dense] [tol] [t_end] [check]\n");
    return 2;
  }
  int n = atoi(argv[1]);
  int use_klu = argc < 3 || strcmp(argv[2], "dense") != 0;
  double tol = argc > 3 ? atof(argv[3]) : 1e-6;
  double t_end = argc > 4 ? atof(argv[4]) : 1.0;
  if (n < 1 || !(tol > 0) || !(t_end > 0)) {
    fprintf(stderr, "ida_chain: need N >= 1, tol > 0, t_end > 0\n");
    return 2;
  }
  sunindextype neq = 5 * (sunindextype)n;
  Jac J = {0};
  J.n = n;
  build_pattern(&J, neq);
  if (argc > 5 && strcmp(argv[5], "check") == 0) return check(&J, neq);

  double t0 = thread_cpu();
  SUNContext ctx;
  if (SUNContext_Create(NULL, &ctx)) fail("SUNContext_Create", 0);
  N_Vector yy = N_VNew_Serial(neq, ctx), yp = N_VNew_Serial(neq, ctx);
  double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  for (int i = 1; i <= n; i++) {
    y[IX(i, 0)] = i * L_LEN;
    y[IX(i, 1)] = y[IX(i, 2)] = y[IX(i, 3)] = y[IX(i, 4)] = 0.0;
  }
  consistent(n, y, p);
  void *mem = IDACreate(ctx);
  if (!mem) fail("IDACreate", 0);
  long flag;
  if ((flag = IDAInit(mem, res_fn, 0.0, yy, yp))) fail("IDAInit", flag);
  if ((flag = IDASStolerances(mem, tol, tol))) fail("IDASStolerances", flag);
  if ((flag = IDASetUserData(mem, &J))) fail("IDASetUserData", flag);
  if ((flag = IDASetMaxNumSteps(mem, 1000000))) fail("IDASetMaxNumSteps", flag);
  if ((flag = IDASetStopTime(mem, t_end))) fail("IDASetStopTime", flag);
  SUNMatrix A;
  SUNLinearSolver LS;
  if (use_klu) {
    J.mode = SPARSE;
    A = SUNSparseMatrix(neq, neq, J.nnz, CSC_MAT, ctx);
    LS = SUNLinSol_KLU(yy, A, ctx);
  } else {
    J.mode = DENSE;
    A = SUNDenseMatrix(neq, neq, ctx);
    LS = SUNLinSol_Dense(yy, A, ctx);
  }
  if (!A || !LS) fail("matrix or linear solver creation", 0);
  if ((flag = IDASetLinearSolver(mem, LS, A))) fail("IDASetLinearSolver", flag);
  if ((flag = IDASetJacFn(mem, jac_fn))) fail("IDASetJacFn", flag);
  double tret = 0.0;
  if ((flag = IDASolve(mem, t_end, &tret, yy, yp, IDA_NORMAL)) < 0) fail("IDASolve", flag);
  double cpu = thread_cpu() - t0;

  long nst, nre, nje, nsetups, netf, ncfn, nni, nreLS;
  IDAGetNumSteps(mem, &nst);
  IDAGetNumResEvals(mem, &nre);
  IDAGetNumJacEvals(mem, &nje);
  IDAGetNumLinSolvSetups(mem, &nsetups);
  IDAGetNumErrTestFails(mem, &netf);
  IDAGetNumNonlinSolvConvFails(mem, &ncfn);
  IDAGetNumNonlinSolvIters(mem, &nni);
  IDAGetNumLinResEvals(mem, &nreLS);
  printf("{\"n\": %d, \"linsol\": \"%s\", \"tol\": %g, \"t_end\": %.17g, \"nnz\": %ld, "
         "\"steps\": %ld, \"error_test_failures\": %ld, \"newton_failures\": %ld, "
         "\"residual_evals\": %ld, \"jacobian_evals\": %ld, \"factorizations\": %ld, "
         "\"newton_iterations\": %ld, \"cpu_s\": %.9f, \"final\": {",
         n, use_klu ? "klu" : "dense", tol, tret, (long)J.nnz, nst, netf, ncfn, nre + nreLS, nje,
         nsetups, nni, cpu);
  for (int i = 1; i <= n; i++)
    printf("\"x%d\": %.17g, \"y%d\": %.17g%s", i, y[IX(i, 0)], i, y[IX(i, 1)], i < n ? ", " : "");
  printf("}}\n");

  IDAFree(&mem);
  SUNLinSolFree(LS);
  SUNMatDestroy(A);
  N_VDestroy(yy);
  N_VDestroy(yp);
  SUNContext_Free(&ctx);
  return 0;
}
