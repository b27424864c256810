/*
 * SUNDIALS IDA on the IVP Test Set's car axis (`caraxis`, scenes/caraxis.dae)
 * in the index-1 form that `dae derive` calls rcd0: the dynamics rows as the
 * model writes them, the two position constraints replaced by their second
 * time derivatives with the accelerations substituted from the dynamics
 * rows. The yardstick of `dae run scenes/caraxis.toml --solver bdf
 * --formulation rcd0` (BENCHMARKS.md §15b: are the BDF family's missing
 * digits on the car axis the method's?). Built and run by
 * scripts/ida_pendulum.sh (CARAXIS_TOLS). Not part of the Rust workspace
 * and not a test.
 *
 * Unknowns (xl, yl, xr, yr, ul, vl, ur, vr, lam1, lam2); with
 * k = m eps^2 / 2, yb = r sin(w t), xb = sqrt(l^2 - yb^2) and the right-hand
 * sides f5..f8 of the model's rows `k der(ul) = f5` ... `k der(vr) = f8`:
 *
 *   x' - u (four rows),   k u' - f (four rows),
 *   g1'' = xb'' xl + 2 xb' ul + xb al + yb'' yl + 2 yb' vl + yb bl,
 *   g2'' = 2 [(ul - ur)^2 + (vl - vr)^2 + (xl - xr)(al - ar) + (yl - yr)(bl - br)],
 *
 * where (al, bl, ar, br) = (f5, f6, f7, f8) / k are the accelerations as
 * the dynamics rows give them (so the last two rows hold lam1, lam2
 * algebraically: index 1). The rows are those of rcd0 up to constant
 * factors, which change nothing in IDA's Newton iteration (its norms are
 * on the unknowns). IDA's difference-quotient dense Jacobian.
 *
 * Usage: ida_caraxis [tol]
 *   From the Test Set's start (xl = 0, yl = 0.5, xr = 1, yr = 0.5,
 *   ul = ur = -0.5, vl = vr = 0; consistent at every level), the
 *   multipliers and the derivatives of the other unknowns computed by
 *   IDACalcIC (IDA_YA_YDP_INIT), over [0, 3] with rtol = atol = tol for
 *   every unknown (as `dae run --tol`, every unknown in the error test),
 *   step by step (IDA_ONE_STEP, stop time 3). Prints one JSON object: the
 *   work counters, the orders of the accepted steps, and scd at t = 3 over
 *   the eight positions and velocities, relative, against the Test Set's
 *   reference (scenes/caraxis_reference.csv), as scenes/caraxis.toml asks.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define IDA_DRIVER "ida_caraxis"
#include "ida_common.h"

static const double EPS = 0.01, MASS = 10.0, L = 1.0, L0 = 0.5, R = 0.1, W = 10.0, G = 1.0;

/* The Test Set's reference at t = 3 (`carsoln` in caraxis.f): positions
 * and velocities. */
static const double REF[8] = {0.4934557842755629e-001, 0.4969894602303324e+000,
                              0.1041742524885400e+001, 0.3739110272652214e+000,
                              -0.7705836840321485e-001, 0.7446866596327776e-002,
                              0.1755681574942899e-001, 0.7703410437794031e+000};

/* The four right-hand sides f5..f8 of the dynamics rows at (t, y). */
static void forces(double t, const double *y, double *f) {
  double k = MASS * EPS * EPS / 2.0;
  double yb = R * sin(W * t), xb = sqrt(L * L - yb * yb);
  double xl = y[0], yl = y[1], xr = y[2], yr = y[3], lam1 = y[8], lam2 = y[9];
  double ll = sqrt(xl * xl + yl * yl);
  double lr = sqrt((xr - xb) * (xr - xb) + (yr - yb) * (yr - yb));
  f[0] = (L0 - ll) * xl / ll + lam1 * xb + 2.0 * lam2 * (xl - xr);
  f[1] = (L0 - ll) * yl / ll + lam1 * yb + 2.0 * lam2 * (yl - yr) - k * G;
  f[2] = (L0 - lr) * (xr - xb) / lr - 2.0 * lam2 * (xl - xr);
  f[3] = (L0 - lr) * (yr - yb) / lr - 2.0 * lam2 * (yl - yr) - k * G;
}

static int res_fn(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)data;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  double k = MASS * EPS * EPS / 2.0;
  double f[4];
  forces(t, y, f);
  for (int i = 0; i < 4; i++) {
    r[i] = p[i] - y[4 + i];
    r[4 + i] = k * p[4 + i] - f[i];
  }
  /* yb, xb and their first two time derivatives. */
  double s = sin(W * t), c = cos(W * t);
  double yb = R * s, ybp = R * W * c, ybpp = -R * W * W * s;
  double xb = sqrt(L * L - yb * yb);
  double xbp = -yb * ybp / xb;
  double xbpp = -(ybp * ybp + yb * ybpp) / xb - xbp * xbp / xb;
  double al = f[0] / k, bl = f[1] / k, ar = f[2] / k, br = f[3] / k;
  double xl = y[0], yl = y[1], xr = y[2], yr = y[3], ul = y[4], vl = y[5], ur = y[6], vr = y[7];
  r[8] = xbpp * xl + 2.0 * xbp * ul + xb * al + ybpp * yl + 2.0 * ybp * vl + yb * bl;
  r[9] = 2.0 * ((ul - ur) * (ul - ur) + (vl - vr) * (vl - vr) + (xl - xr) * (al - ar) +
                (yl - yr) * (bl - br));
  return 0;
}

int main(int argc, char **argv) {
  double tol = argc > 1 ? atof(argv[1]) : 1e-6;
  const double t_end = 3.0;
  if (!(tol > 0)) {
    fprintf(stderr, "usage: ida_caraxis [tol > 0]\n");
    return 2;
  }
  SUNContext ctx;
  if (SUNContext_Create(NULL, &ctx)) fail("SUNContext_Create", 0);
  N_Vector yy = N_VNew_Serial(10, ctx), yp = N_VNew_Serial(10, ctx), id = N_VNew_Serial(10, ctx);
  double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp), *d = N_VGetArrayPointer(id);
  const double y0[10] = {0.0, L0, L, L0, -L0 / L, 0.0, -L0 / L, 0.0, 0.0, 0.0};
  for (int i = 0; i < 10; i++) y[i] = y0[i], p[i] = 0.0, d[i] = i < 8 ? 1.0 : 0.0;
  for (int i = 0; i < 4; i++) p[i] = y[4 + i];
  void *mem = ida_start(ctx, res_fn, yy, yp, tol, t_end);
  long flag;
  if ((flag = IDASetId(mem, id))) fail("IDASetId", flag);
  SUNMatrix A = SUNDenseMatrix(10, 10, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(yy, A, ctx);
  if ((flag = IDASetLinearSolver(mem, LS, A))) fail("IDASetLinearSolver", flag);
  if ((flag = IDACalcIC(mem, IDA_YA_YDP_INIT, 1e-6))) fail("IDACalcIC", flag);
  if ((flag = IDAGetConsistentIC(mem, yy, yp))) fail("IDAGetConsistentIC", flag);
  double lam0[2] = {y[8], y[9]};

  struct ida_run run;
  ida_steps(mem, t_end, yy, yp, &run);
  struct ida_counts counts = ida_counts(mem);
  double worst = 0.0;
  for (int i = 0; i < 8; i++) {
    double e = fabs((y[i] - REF[i]) / REF[i]);
    if (e > worst) worst = e;
  }
  printf("{\"tol\": %g, \"t_end\": %.17g, ", tol, run.tret);
  ida_print_counts(&counts, &run);
  printf(", \"lambda0\": [%.6e, %.6e], \"scd\": %.2f}\n", lam0[0], lam0[1], -log10(worst));
  N_VDestroy(id);
  ida_finish(mem, LS, A, yy, yp, ctx);
  return 0;
}
