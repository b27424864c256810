/*
 * SUNDIALS IDA on the IVP Test Set's transistor amplifier (`transamp`,
 * scenes/transamp.dae) in its published form M y' = f(t, y): the residual
 * F(t, y, y') = M y' - f(t, y), row by row as scenes/transamp.dae writes
 * them (the Test Set's `feval`/`meval`). The DASSL-class yardstick of
 * `dae run scenes/transamp.toml --solver bdf` (BENCHMARKS.md §15b, issue 26
 * done-when 2: bdf on index-1 problems needs no more steps than DASSL-class
 * codes). Built and run by scripts/ida_pendulum.sh. Not part of the Rust
 * workspace and not a test.
 *
 * Usage: ida_transamp [tol] [max_order] [nonlin_conv_coef]
 *   Integrates over the Test Set's [0, 0.2] from its consistent start
 *   (`init`: y2 = y3 = y5 = y6 = 3, y4 = y7 = 6, y1 = y8 = 0, and the
 *   y'(0) consistent with it, see consistent_yp) with
 *   rtol = atol = tol for every unknown (as `dae run --tol`), IDA's
 *   difference-quotient dense Jacobian, step by step (IDA_ONE_STEP, stop
 *   time 0.2), and prints one JSON object: the work counters, the histogram
 *   of the orders of the accepted steps, and scd, the Test Set's significant
 *   correct digits at t = 0.2 (-log10 of the largest relative error against
 *   its reference, scenes/transamp_reference.csv). nonlin_conv_coef is
 *   IDA's bound on the Newton iterate's estimated error in the weighted
 *   norm (IDASetNonlinConvCoef; default 0.33, DASSL's): BENCHMARKS.md §15b
 *   measures what a tighter bound does to the crawl at tight tolerances.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define IDA_DRIVER "ida_transamp"
#include "ida_common.h"

static const double UB = 6.0, UF = 0.026, ALPHA = 0.99, BETA = 1e-6, R0 = 1000.0, RK = 9000.0,
                    C1 = 1e-6, C2 = 2e-6, C3 = 3e-6, C4 = 4e-6, C5 = 5e-6;
static const double PI = 3.1415926535897931;

/* The Test Set's reference at t = 0.2 (`solut` in transamp.f). */
static const double REF[8] = {
    -0.5562145012262709e-002, 0.3006522471903042e+001, 0.2849958788608128e+001,
    0.2926422536206241e+001,  0.2704617865010554e+001, 0.2761837778393145e+001,
    0.4770927631616772e+001,  0.1236995868091548e+001};

static int res_fn(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)data;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  double uet = 0.1 * sin(200.0 * PI * t);
  double g1 = BETA * (exp((y[1] - y[2]) / UF) - 1.0);
  double g2 = BETA * (exp((y[4] - y[5]) / UF) - 1.0);
  r[0] = -C1 * p[0] + C1 * p[1] - (y[0] - uet) / R0;
  r[1] = C1 * p[0] - C1 * p[1] - (y[1] / RK + (y[1] - UB) / RK + (1.0 - ALPHA) * g1);
  r[2] = -C2 * p[2] - (y[2] / RK - g1);
  r[3] = -C3 * p[3] + C3 * p[4] - ((y[3] - UB) / RK + ALPHA * g1);
  r[4] = C3 * p[3] - C3 * p[4] - (y[4] / RK + (y[4] - UB) / RK + (1.0 - ALPHA) * g2);
  r[5] = -C4 * p[5] - (y[5] / RK - g2);
  r[6] = -C5 * p[6] + C5 * p[7] - ((y[6] - UB) / RK + ALPHA * g2);
  r[7] = C5 * p[6] - C5 * p[7] - y[7] / RK;
  return 0;
}

/* The consistent y'(0) at t = 0. The pairs of rows (1, 2), (4, 5), (7, 8)
 * fix the differences y2' - y1' = f1/C1, y5' - y4' = f4/C3,
 * y8' - y7' = f7/C5, and rows 3 and 6 fix y3' = -f3/C2, y6' = -f6/C4; the
 * sums of the pairs are algebraic conditions (f1 + f2 = 0, f4 + f5 = 0,
 * f7 + f8 = 0, which the start satisfies), whose time derivatives fix the
 * remaining y2', y5', y8' (each linear in it once the others are known). */
static void consistent_yp(const double *y, double *p) {
  double g1p = BETA / UF * exp((y[1] - y[2]) / UF);
  double g2p = BETA / UF * exp((y[4] - y[5]) / UF);
  double g1 = BETA * (exp((y[1] - y[2]) / UF) - 1.0);
  double g2 = BETA * (exp((y[4] - y[5]) / UF) - 1.0);
  double uet = 0.0, uetp = 0.1 * 200.0 * PI; /* Ue and Ue' at t = 0 */
  double d12 = (y[0] - uet) / R0 / C1;
  double d45 = ((y[3] - UB) / RK + ALPHA * g1) / C3;
  double d78 = ((y[6] - UB) / RK + ALPHA * g2) / C5;
  p[2] = -(y[2] / RK - g1) / C2;
  p[5] = -(y[5] / RK - g2) / C4;
  /* d/dt (f1 + f2) = (y1' - Ue')/R0 + 2 y2'/RK + (1-a) g1' (y2' - y3') = 0, y1' = y2' - d12. */
  p[1] = ((d12 + uetp) / R0 + (1.0 - ALPHA) * g1p * p[2]) / (1.0 / R0 + 2.0 / RK + (1.0 - ALPHA) * g1p);
  p[0] = p[1] - d12;
  /* d/dt (f4 + f5) = y4'/RK + a g1' (y2' - y3') + 2 y5'/RK + (1-a) g2' (y5' - y6') = 0, y4' = y5' - d45. */
  p[4] = (d45 / RK - ALPHA * g1p * (p[1] - p[2]) + (1.0 - ALPHA) * g2p * p[5]) /
         (3.0 / RK + (1.0 - ALPHA) * g2p);
  p[3] = p[4] - d45;
  /* d/dt (f7 + f8) = y7'/RK + a g2' (y5' - y6') + y8'/RK = 0, y7' = y8' - d78. */
  p[7] = (d78 / RK - ALPHA * g2p * (p[4] - p[5])) / (2.0 / RK);
  p[6] = p[7] - d78;
}

int main(int argc, char **argv) {
  double tol = argc > 1 ? atof(argv[1]) : 1e-6;
  int max_order = argc > 2 ? atoi(argv[2]) : 5;
  double conv_coef = argc > 3 ? atof(argv[3]) : 0.33;
  const double t_end = 0.2;
  if (!(tol > 0) || max_order < 1 || max_order > 5 || !(conv_coef > 0)) {
    fprintf(stderr, "usage: ida_transamp [tol > 0] [max_order 1..5] [nonlin_conv_coef > 0]\n");
    return 2;
  }
  SUNContext ctx;
  if (SUNContext_Create(NULL, &ctx)) fail("SUNContext_Create", 0);
  N_Vector yy = N_VNew_Serial(8, ctx), yp = N_VNew_Serial(8, ctx);
  double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  const double y0[8] = {0.0, 3.0, 3.0, 6.0, 3.0, 3.0, 6.0, 0.0};
  for (int i = 0; i < 8; i++) y[i] = y0[i];
  consistent_yp(y, p);
  void *mem = ida_start(ctx, res_fn, yy, yp, tol, t_end);
  long flag;
  if ((flag = IDASetMaxOrd(mem, max_order))) fail("IDASetMaxOrd", flag);
  if ((flag = IDASetNonlinConvCoef(mem, conv_coef))) fail("IDASetNonlinConvCoef", flag);
  SUNMatrix A = SUNDenseMatrix(8, 8, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(yy, A, ctx);
  if ((flag = IDASetLinearSolver(mem, LS, A))) fail("IDASetLinearSolver", flag);

  struct ida_run run;
  ida_steps(mem, t_end, yy, yp, &run);
  struct ida_counts counts = ida_counts(mem);
  double worst = 0.0;
  for (int i = 0; i < 8; i++) {
    double e = fabs((y[i] - REF[i]) / REF[i]);
    if (e > worst) worst = e;
  }
  printf("{\"tol\": %g, \"t_end\": %.17g, \"max_order\": %d, \"conv_coef\": %g, ", tol,
         run.tret, max_order, conv_coef);
  ida_print_counts(&counts, &run);
  printf(", \"scd\": %.2f}\n", -log10(worst));
  ida_finish(mem, LS, A, yy, yp, ctx);
  return 0;
}
