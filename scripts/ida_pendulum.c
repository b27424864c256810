/*
 * SUNDIALS IDA on the pendulum of scenes/pendulum.dae (the SPEC's S01: m = l
 * = 1, g = 13.7503716373294544, released horizontally at rest, period 2 s
 * to 1e-10) in the index-1 form that `dae derive` calls rcd0: the position
 * constraint replaced by its second time derivative with the accelerations
 * substituted. The yardstick of the BDF family's accuracy at tight
 * tolerances (BENCHMARKS.md §15b, issue 25 done-when 1, issue 26 done-when
 * 2); built and run by scripts/ida_pendulum.sh. Not part of the Rust
 * workspace and not a test.
 *
 * Unknowns (x, y, v, w, la); IDA's residual F(t, y, y') = E y' - f(y) row
 * by row as dae's rows are written:
 *
 *   x' - v,   y' - w,   m v' + 2 x la,   m w' + 2 y la + m g,
 *   2 (v^2 + w^2) - 4 la (x^2 + y^2) / m - 2 g y          (rcd0's row),
 *
 * with the analytic dense Jacobian. rtol = atol = tol for every unknown (as
 * `dae run --tol`), every unknown in the error test (la is of index 1 in
 * rcd0; dae's bdf tests it too), maximum order 5 unless given.
 *
 * Usage: ida_pendulum [tol] [t_end] [max_order]
 *   Integrates from (1, 0, 0, 0, 0), y'(0) = (0, 0, 0, -g, 0) (consistent:
 *   la(0) = 0, la'(0) = 0 from the constraint chain) over [0, t_end]
 *   (default 10: five periods, the events test's horizon), step by step
 *   (IDA_ONE_STEP, stop time t_end), with IDA's root finder on x. Prints
 *   one JSON object: the work counters, the histogram of the orders of the
 *   accepted steps, each located zero crossing of x against the exact
 *   (2k+1) T / 4 (T = 4 sqrt(l/g) K(1/sqrt 2), K by the arithmetic-
 *   geometric mean), the worst of them, and the final state. When t_end is
 *   a whole number of half periods within 1e-6 the final state is also
 *   compared with the exact one there (first order in the distance to the
 *   nearest multiple of T/2, enough for S01's t = 20 = 10 T + 9.4e-10).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define IDA_DRIVER "ida_pendulum"
#include "ida_common.h"

#define M_MASS 1.0
#define L_LEN 1.0
#define G_ACC 13.7503716373294544

static int res_fn(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)t;
  (void)data;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  double x = y[0], z = y[1], v = y[2], w = y[3], la = y[4];
  r[0] = p[0] - v;
  r[1] = p[1] - w;
  r[2] = M_MASS * p[2] + 2.0 * x * la;
  r[3] = M_MASS * p[3] + 2.0 * z * la + M_MASS * G_ACC;
  r[4] = 2.0 * (v * v + w * w) - 4.0 * la * (x * x + z * z) / M_MASS - 2.0 * G_ACC * z;
  return 0;
}

/* dF/dy + cj dF/dy'. */
static int jac_fn(realtype t, realtype cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J,
                  void *data, N_Vector t1, N_Vector t2, N_Vector t3) {
  (void)t, (void)yp, (void)rr, (void)data, (void)t1, (void)t2, (void)t3;
  const double *y = N_VGetArrayPointer(yy);
  double x = y[0], z = y[1], v = y[2], w = y[3], la = y[4];
  SUNMatZero(J);
#define E(i, j) SM_ELEMENT_D(J, i, j)
  E(0, 0) = cj, E(0, 2) = -1.0;
  E(1, 1) = cj, E(1, 3) = -1.0;
  E(2, 2) = M_MASS * cj, E(2, 0) = 2.0 * la, E(2, 4) = 2.0 * x;
  E(3, 3) = M_MASS * cj, E(3, 1) = 2.0 * la, E(3, 4) = 2.0 * z;
  E(4, 0) = -8.0 * la * x / M_MASS;
  E(4, 1) = -8.0 * la * z / M_MASS - 2.0 * G_ACC;
  E(4, 2) = 4.0 * v, E(4, 3) = 4.0 * w;
  E(4, 4) = -4.0 * (x * x + z * z) / M_MASS;
#undef E
  return 0;
}

static int root_fn(realtype t, N_Vector yy, N_Vector yp, realtype *g, void *data) {
  (void)t, (void)yp, (void)data;
  g[0] = N_VGetArrayPointer(yy)[0];
  return 0;
}

/* The period released horizontally: 4 sqrt(l/g) K(sin(pi/4)). */
static double period(void) {
  double a = 1.0, b = sqrt(0.5);
  for (int i = 0; i < 32 && fabs(a - b) > 4.0 * 2.220446049250313e-16 * a; i++) {
    double an = 0.5 * (a + b);
    b = sqrt(a * b);
    a = an;
  }
  double k = M_PI / (a + b);
  return 4.0 * sqrt(L_LEN / G_ACC) * k;
}

int main(int argc, char **argv) {
  double tol = argc > 1 ? atof(argv[1]) : 1e-10;
  double t_end = argc > 2 ? atof(argv[2]) : 10.0;
  int max_order = argc > 3 ? atoi(argv[3]) : 5;
  if (!(tol > 0) || !(t_end > 0) || max_order < 1 || max_order > 5) {
    fprintf(stderr, "usage: ida_pendulum [tol > 0] [t_end > 0] [max_order 1..5]\n");
    return 2;
  }
  SUNContext ctx;
  if (SUNContext_Create(NULL, &ctx)) fail("SUNContext_Create", 0);
  N_Vector yy = N_VNew_Serial(5, ctx), yp = N_VNew_Serial(5, ctx);
  double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  for (int i = 0; i < 5; i++) y[i] = p[i] = 0.0;
  y[0] = L_LEN;
  p[3] = -G_ACC;
  void *mem = ida_start(ctx, res_fn, yy, yp, tol, t_end);
  long flag;
  if ((flag = IDASetMaxOrd(mem, max_order))) fail("IDASetMaxOrd", flag);
  if ((flag = IDARootInit(mem, 1, root_fn))) fail("IDARootInit", flag);
  SUNMatrix A = SUNDenseMatrix(5, 5, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(yy, A, ctx);
  if ((flag = IDASetLinearSolver(mem, LS, A))) fail("IDASetLinearSolver", flag);
  if ((flag = IDASetJacFn(mem, jac_fn))) fail("IDASetJacFn", flag);

  double T = period();
  struct ida_run run;
  ida_steps(mem, t_end, yy, yp, &run);
  struct ida_counts counts = ida_counts(mem);
  double tret = run.tret;
  printf("{\"tol\": %g, \"t_end\": %.17g, \"max_order\": %d, \"period\": %.17g, ", tol, tret,
         max_order, T);
  ida_print_counts(&counts, &run);
  printf(", \"crossings\": [");
  double worst = 0.0;
  for (int k = 0; k < run.nroots; k++) {
    double err = run.roots[k] - (2 * k + 1) * T / 4.0;
    if (fabs(err) > worst) worst = fabs(err);
    printf("%s%.3e", k ? ", " : "", err);
  }
  printf("], \"worst_crossing_error\": %.3e, \"final\": [%.17g, %.17g, %.17g, %.17g, %.17g]",
         worst, y[0], y[1], y[2], y[3], y[4]);
  /* Near a multiple of T/2 the bob is at rest at x = +-1, y = 0; a time d
   * after it, to first order, w = -g d and the other unknowns move by
   * O(d^2). */
  double halves = round(2.0 * tret / T), d = tret - halves * T / 2.0;
  if (fabs(d) < 1e-6) {
    double ex[4] = {((long)halves % 2) ? -L_LEN : L_LEN, 0.0, 0.0, -G_ACC * d};
    double err = 0.0;
    for (int i = 0; i < 4; i++)
      if (fabs(y[i] - ex[i]) > err) err = fabs(y[i] - ex[i]);
    printf(", \"final_error\": %.3e", err);
  }
  printf("}\n");

  ida_finish(mem, LS, A, yy, yp, ctx);
  return 0;
}
