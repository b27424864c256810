/*
 * SUNDIALS IDA on the index-1 problems of the literature map that no other
 * driver covers: the IVP Test Set's chemical Akzo Nobel problem as the
 * model writes it (index 1), and the rcd0 forms (as `dae derive` prints
 * them) of Jay's index-2 problem, Gear–Hsu–Petzold's, Pantelides' reactor
 * and the CV-loop circuit. The yardstick of issue 26's "bdf on index-1
 * problems needs no more steps than DASSL-class codes for the same problem
 * and tolerance (within 2x)": scripts/ida_index1.sh runs it beside `dae run
 * --solver bdf --formulation rcd0` (EXTREMES.md section 5, "Session 13").
 * Not part of the Rust workspace and not a test.
 *
 * Usage: ida_index1 PROBLEM TOL
 *   PROBLEM: chemakzo | jay | ghp | cstr | mna. From the scene's start
 *   (scenes/literature/PROBLEM.toml), the algebraic unknowns and every
 *   derivative made consistent by IDACalcIC (IDA_YA_YDP_INIT), except
 *   Gear–Hsu–Petzold's, whose exact start is given (its leading matrix
 *   [1, t; 0, 0] has no constant split into differential and algebraic
 *   unknowns). rtol = atol = TOL for every unknown (as `dae run --tol`),
 *   IDA's dense difference-quotient Jacobian, output at the scene's check
 *   times (IDA_NORMAL: IDA interpolates, its steps do not stop there),
 *   the stop time t_end. Prints one JSON object: the work counters, and
 *   the solution at the check times (`"t"`, `"y"`) for the script to score
 *   against the scene's reference.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define IDA_DRIVER "ida_index1"
#include "ida_common.h"

/* The Test Set's chemakzo constants (chemakzo.f, `chemakzo_feval`). */
static const double K1 = 18.7, K2 = 0.58, K3 = 0.09, K4 = 0.42, KBIG = 34.4, KLA = 3.3,
                    KS = 115.83, PO2 = 0.9, HEN = 737.0;

static int res_chemakzo(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)t, (void)data;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  if (y[1] < 0.0) return 1; /* sqrt(y2): a recoverable failure, as the Test Set's ierr */
  double r1 = K1 * pow(y[0], 4) * sqrt(y[1]), r2 = K2 * y[2] * y[3];
  double r3 = K2 / KBIG * y[0] * y[4], r4 = K3 * y[0] * y[3] * y[3];
  double r5 = K4 * y[5] * y[5] * sqrt(y[1]), fin = KLA * (PO2 / HEN - y[1]);
  r[0] = p[0] - (-2.0 * r1 + r2 - r3 - r4);
  r[1] = p[1] - (-0.5 * r1 - r4 - 0.5 * r5 + fin);
  r[2] = p[2] - (r1 - r2 + r3);
  r[3] = p[3] - (-r2 + r3 - 2.0 * r4);
  r[4] = p[4] - (r2 - r3 + r5);
  r[5] = KS * y[0] * y[3] - y[5];
  return 0;
}

/* Jay's problem in rcd0: (y1, y2, z). */
static int res_jay(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)t, (void)data;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  double y1 = y[0], y2 = y[1], z = y[2];
  r[0] = p[0] - y1 * y2 * y2 * z * z;
  r[1] = p[1] - (y1 * y1 * y2 * y2 - 3.0 * y2 * y2 * z);
  r[2] = 2.0 * y1 * y1 * pow(y2, 3) * z * z + pow(y1, 4) * y2 * y2 - 3.0 * y1 * y1 * y2 * y2 * z;
  return 0;
}

/* Gear–Hsu–Petzold in rcd0, eta = 1: (y1, y2). */
static int res_ghp(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)data;
  const double eta = 1.0;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  r[0] = p[0] + eta * t * p[1] - (sin(t) - y[1] - eta * y[1]);
  r[1] = sin(t) + exp(-t) - y[1];
  return 0;
}

/* Pantelides' reactor in rcd0, every constant 1: (C, T, R, TC). */
static int res_cstr(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)data;
  const double k1 = 1, k2 = 1, k3 = 1, k4 = 1, k5 = 1, c0 = 1, tf0 = 1;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  double C = y[0], T = y[1], R = y[2], TC = y[3], ex = exp(-k4 / T);
  r[0] = p[0] - (k1 * c0 - R - k1 * C);
  r[1] = p[1] - (k2 * R + k1 * tf0 - k1 * T - k3 * (T - TC));
  r[2] = R - k5 * C * ex;
  r[3] = k3 * k4 * k5 * C * (T - TC) * ex / (T * T) + k1 * k4 * k5 * C * ex / T +
         k1 * k5 * C * ex + k1 * k1 * C + k1 * R + k5 * R * ex + sin(t) / 10.0 -
         k2 * k4 * k5 * C * R * ex / (T * T) - k1 * k4 * k5 * tf0 * C * ex / (T * T) -
         k1 * k5 * c0 * ex - k1 * k1 * c0;
  return 0;
}

/* The CV-loop circuit in rcd0, every constant 1: (e1, e2, e3, jv). */
static int res_mna(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  (void)data;
  const double c1 = 1, c2 = 1, r1 = 1, r2 = 1, v0 = 1, w = 1;
  const double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  r[0] = c1 * p[1] + c2 * p[1] - c1 * p[0] + (y[1] - y[2]) / r1;
  r[1] = c1 * p[0] - c1 * p[1] + y[3];
  r[2] = y[2] / r2 - (y[1] - y[2]) / r1;
  r[3] = p[0] - v0 * w * cos(w * t);
  return 0;
}

/* One problem: its size, residual, start (y, y'), which unknowns are
 * differential (for IDACalcIC; NULL: the start is consistent as given),
 * horizon and check times (every `every` from `every` to t_end). */
struct problem {
  const char *name;
  int n;
  IDAResFn res;
  double y0[6], yp0[6];
  const double *id;
  double t_end, every;
};

static const double ID_CHEMAKZO[6] = {1, 1, 1, 1, 1, 0};
static const double ID_JAY[3] = {1, 1, 0};
static const double ID_TWO[4] = {1, 1, 0, 0};

static const struct problem PROBLEMS[] = {
    {"chemakzo", 6, res_chemakzo, {0.444, 0.00123, 0.0, 0.007, 0.0, 0.35999964}, {0}, ID_CHEMAKZO,
     180.0, 180.0},
    {"jay", 3, res_jay, {1.0, 1.0, 1.0}, {0}, ID_JAY, 1.0, 0.1},
    {"ghp", 2, res_ghp, {1.0, 1.0}, {-2.0, 0.0}, NULL, 3.0, 0.25},
    {"cstr", 4, res_cstr, {0.5, 4.481420117724549786893047, 0.0, 0.0}, {0}, ID_TWO, 1.0, 0.1},
    {"mna", 4, res_mna, {0.0, 0.0, 0.0, -0.5}, {1.0, 0.5, 0.0, 0.0}, ID_TWO, 10.0, 0.5},
};

int main(int argc, char **argv) {
  const struct problem *pb = NULL;
  for (size_t i = 0; argc > 1 && i < sizeof PROBLEMS / sizeof *PROBLEMS; i++)
    if (!strcmp(argv[1], PROBLEMS[i].name)) pb = &PROBLEMS[i];
  double tol = argc > 2 ? atof(argv[2]) : 0.0;
  if (!pb || !(tol > 0)) {
    fprintf(stderr, "usage: ida_index1 chemakzo|jay|ghp|cstr|mna TOL\n");
    return 2;
  }
  SUNContext ctx;
  if (SUNContext_Create(NULL, &ctx)) fail("SUNContext_Create", 0);
  int n = pb->n;
  N_Vector yy = N_VNew_Serial(n, ctx), yp = N_VNew_Serial(n, ctx);
  double *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp);
  for (int i = 0; i < n; i++) y[i] = pb->y0[i], p[i] = pb->yp0[i];
  void *mem = ida_start(ctx, pb->res, yy, yp, tol, pb->t_end);
  long flag;
  SUNMatrix A = SUNDenseMatrix(n, n, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(yy, A, ctx);
  if ((flag = IDASetLinearSolver(mem, LS, A))) fail("IDASetLinearSolver", flag);
  if (pb->id) {
    N_Vector id = N_VNew_Serial(n, ctx);
    for (int i = 0; i < n; i++) N_VGetArrayPointer(id)[i] = pb->id[i];
    if ((flag = IDASetId(mem, id))) fail("IDASetId", flag);
    if ((flag = IDACalcIC(mem, IDA_YA_YDP_INIT, pb->every))) fail("IDACalcIC", flag);
    if ((flag = IDAGetConsistentIC(mem, yy, yp))) fail("IDAGetConsistentIC", flag);
    N_VDestroy(id);
  }
  printf("{\"problem\": \"%s\", \"tol\": %g, \"t\": [", pb->name, tol);
  int checks = (int)lround(pb->t_end / pb->every);
  static double out[1000][6];
  double tret = 0.0;
  for (int k = 1; k <= checks; k++) {
    double tout = k == checks ? pb->t_end : k * pb->every;
    if ((flag = IDASolve(mem, tout, &tret, yy, yp, IDA_NORMAL)) < 0) fail("IDASolve", flag);
    for (int i = 0; i < n; i++) out[k - 1][i] = y[i];
    printf("%s%.17g", k > 1 ? ", " : "", tret);
  }
  printf("], \"y\": [");
  for (int k = 0; k < checks; k++) {
    printf("%s[", k ? ", " : "");
    for (int i = 0; i < n; i++) printf("%s%.17g", i ? ", " : "", out[k][i]);
    printf("]");
  }
  printf("], ");
  struct ida_counts c = ida_counts(mem);
  struct ida_run none = {0};
  ida_print_counts(&c, &none);
  printf("}\n");
  ida_finish(mem, LS, A, yy, yp, ctx);
  return 0;
}
