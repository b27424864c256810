/*
 * SUNDIALS IDA on Jay's index-2 problem as written (`ori2` of
 * scenes/jay_index2.dae, the rows `dae derive` prints):
 *
 *   y1' = y1 y2^2 z^2,   y2' = y1^2 y2^2 - 3 y2^2 z,   0 = y1^2 y2 - 1,
 *
 * from the exact start y1 = y2 = z = 1 (y' = (1, -2, 2)) to t = 1. The
 * DASSL-class yardstick of `bdf(ori2)` on this problem (EXTREMES.md
 * "jay15"): with z out of IDA's error test (IDASetSuppressAlg, as DASPK's
 * INFO(16) and `bdf`'s default) and, for comparison, with it in.
 * rtol = atol = TOL for every unknown (as `dae run --tol`), IDA's dense
 * difference-quotient Jacobian, output at t = 0.1, 0.2, ..., 1 (IDA
 * interpolates there). Prints the steps, the error-test failures and the
 * largest relative error of y1, y2 and z over those ten times against the
 * exact solution exp(t), exp(-2t), exp(2t) — the scene's check times and
 * scaling — with its scd (-log10 of the largest of the three).
 *
 *   gcc -O2 -Iscripts -o /tmp/ida_jay_ori2 scripts/ida_jay_ori2.c -lsundials_ida \
 *       -lsundials_nvecserial -lsundials_sunlinsoldense -lsundials_sunmatrixdense -lm
 *   for t in 1e-4 1e-5 1e-6 1e-7 1e-8 1e-9 1e-10; do /tmp/ida_jay_ori2 $t 1; done
 *
 * Usage: ida_jay_ori2 TOL [SUPPRESS] (SUPPRESS 1, the default: z out of
 * the error test; 0: in it). Not part of the Rust workspace and not a test.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define IDA_DRIVER "ida_jay_ori2"
#include "ida_common.h"

static int res_jay(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)t, (void)data;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  double y1 = y[0], y2 = y[1], z = y[2];
  r[0] = p[0] - y1 * y2 * y2 * z * z;
  r[1] = p[1] - (y1 * y1 * y2 * y2 - 3.0 * y2 * y2 * z);
  r[2] = y1 * y1 * y2 - 1.0;
  return 0;
}

int main(int argc, char **argv) {
  double tol = argc > 1 ? atof(argv[1]) : 0.0;
  int suppress = argc > 2 ? atoi(argv[2]) : 1;
  if (!(tol > 0)) {
    fprintf(stderr, "usage: ida_jay_ori2 TOL [SUPPRESS 0|1]\n");
    return 2;
  }
  SUNContext ctx;
  if (SUNContext_Create(NULL, &ctx)) fail("SUNContext_Create", 0);
  N_Vector yy = N_VNew_Serial(3, ctx), yp = N_VNew_Serial(3, ctx), id = N_VNew_Serial(3, ctx);
  double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp), *d = N_VGetArrayPointer(id);
  const double y0[3] = {1.0, 1.0, 1.0}, yp0[3] = {1.0, -2.0, 2.0}, kind[3] = {1.0, 1.0, 0.0};
  for (int i = 0; i < 3; i++) y[i] = y0[i], p[i] = yp0[i], d[i] = kind[i];
  void *mem = ida_start(ctx, res_jay, yy, yp, tol, 1.0);
  SUNMatrix A = SUNDenseMatrix(3, 3, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(yy, A, ctx);
  long flag;
  if ((flag = IDASetLinearSolver(mem, LS, A))) fail("IDASetLinearSolver", flag);
  if ((flag = IDASetId(mem, id))) fail("IDASetId", flag);
  if ((flag = IDASetSuppressAlg(mem, suppress))) fail("IDASetSuppressAlg", flag);
  double worst[3] = {0.0, 0.0, 0.0}, tret = 0.0;
  const char *status = "ok";
  for (int k = 1; k <= 10; k++) {
    if (IDASolve(mem, 0.1 * k, &tret, yy, yp, IDA_NORMAL) < 0) {
      status = "failed";
      break;
    }
    const double exact[3] = {exp(tret), exp(-2.0 * tret), exp(2.0 * tret)};
    for (int i = 0; i < 3; i++) worst[i] = fmax(worst[i], fabs(y[i] / exact[i] - 1.0));
  }
  long nst = 0, netf = 0, nre = 0;
  IDAGetNumSteps(mem, &nst);
  IDAGetNumErrTestFails(mem, &netf);
  IDAGetNumResEvals(mem, &nre);
  printf("tol %g suppress %d %s at t = %g: steps %ld error-test failures %ld residuals %ld", tol,
         suppress, status, tret, nst, netf, nre);
  if (*status == 'o')
    printf(" err y1 %.2e y2 %.2e z %.2e scd %.2f", worst[0], worst[1], worst[2],
           -log10(fmax(worst[0], fmax(worst[1], worst[2]))));
  printf("\n");
  N_VDestroy(id);
  ida_finish(mem, LS, A, yy, yp, ctx);
  return 0;
}
