/*
 * What the SUNDIALS IDA drivers of scripts/ (ida_pendulum.c, ida_transamp.c,
 * ida_caraxis.c) share: the failure exit, the step-by-step integration with
 * the histogram of the accepted steps' orders (and the roots IDA's root
 * finder returns), and the work counters. A header of static functions, so
 * each driver stays one file to compile: `gcc -O2 driver.c -lsundials_ida
 * ...` (scripts/ida_pendulum.sh). Not part of the Rust workspace.
 */
#ifndef DAE_SCRIPTS_IDA_COMMON_H
#define DAE_SCRIPTS_IDA_COMMON_H

#include <stdio.h>
#include <stdlib.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

/* The driver's name in failure messages: each driver defines IDA_DRIVER
 * before including this header. */
#ifndef IDA_DRIVER
#error "define IDA_DRIVER (the driver's name) before including ida_common.h"
#endif

/* Exit with a message naming the SUNDIALS call that failed. */
static void fail(const char *what, long flag) {
  fprintf(stderr, IDA_DRIVER ": %s failed (flag %ld)\n", what, flag);
  exit(1);
}

/* At most this many roots are kept. */
#define IDA_MAX_ROOTS 64

/* What a run returns besides the solution. */
struct ida_run {
  double tret;                   /* the time reached (t_end) */
  long hist[6];                  /* accepted steps per order 1..5 (hist[0] unused) */
  double roots[IDA_MAX_ROOTS];   /* the times of IDA_ROOT_RETURN, in order */
  int nroots;
};

/* Integrate to the stop time t_end (set by the caller with IDASetStopTime)
 * one step at a time (IDA_ONE_STEP), counting the order of every accepted
 * step and keeping the roots. */
static inline void ida_steps(void *mem, double t_end, N_Vector yy, N_Vector yp, struct ida_run *r) {
  long nst_prev = 0;
  r->tret = 0.0;
  r->nroots = 0;
  for (int k = 0; k < 6; k++) r->hist[k] = 0;
  while (r->tret < t_end) {
    long flag = IDASolve(mem, t_end, &r->tret, yy, yp, IDA_ONE_STEP);
    if (flag < 0) fail("IDASolve", flag);
    long nst;
    int kused;
    IDAGetNumSteps(mem, &nst);
    if (nst > nst_prev) {
      IDAGetLastOrder(mem, &kused);
      r->hist[kused] += nst - nst_prev;
      nst_prev = nst;
    }
    if (flag == IDA_ROOT_RETURN && r->nroots < IDA_MAX_ROOTS) r->roots[r->nroots++] = r->tret;
    if (flag == IDA_TSTOP_RETURN) break;
  }
}

/* IDA's work counters, named as `dae run` names its own. */
struct ida_counts {
  long steps, error_test_failures, newton_failures, residual_evals, jacobian_evals,
      factorizations, newton_iterations;
};

/* The counters after a run. Residual evaluations include those of a
 * difference-quotient Jacobian (IDAGetNumLinResEvals; 0 with an analytic
 * one), which is what a `dae` residual count holds too. */
static struct ida_counts ida_counts(void *mem) {
  struct ida_counts c;
  long nre, nre_ls;
  IDAGetNumSteps(mem, &c.steps);
  IDAGetNumResEvals(mem, &nre);
  IDAGetNumLinResEvals(mem, &nre_ls);
  c.residual_evals = nre + nre_ls;
  IDAGetNumJacEvals(mem, &c.jacobian_evals);
  IDAGetNumLinSolvSetups(mem, &c.factorizations);
  IDAGetNumErrTestFails(mem, &c.error_test_failures);
  IDAGetNumNonlinSolvConvFails(mem, &c.newton_failures);
  IDAGetNumNonlinSolvIters(mem, &c.newton_iterations);
  return c;
}

/* Print the counters and the order histogram as JSON members (no braces),
 * in the order the drivers have always printed them. */
static void ida_print_counts(const struct ida_counts *c, const struct ida_run *r) {
  printf("\"steps\": %ld, \"error_test_failures\": %ld, \"newton_failures\": %ld, "
         "\"residual_evals\": %ld, \"jacobian_evals\": %ld, \"factorizations\": %ld, "
         "\"newton_iterations\": %ld, \"orders\": [%ld, %ld, %ld, %ld, %ld]",
         c->steps, c->error_test_failures, c->newton_failures, c->residual_evals,
         c->jacobian_evals, c->factorizations, c->newton_iterations, r->hist[1], r->hist[2],
         r->hist[3], r->hist[4], r->hist[5]);
}

/* IDA set up for `res` from (yy, yp) at t = 0: rtol = atol = tol for every
 * unknown (as `dae run --tol`), a step limit no run reaches, the stop time
 * t_end. The caller adds its own settings and the linear solver. */
static void *ida_start(SUNContext ctx, IDAResFn res, N_Vector yy, N_Vector yp, double tol,
                       double t_end) {
  void *mem = IDACreate(ctx);
  if (!mem) fail("IDACreate", 0);
  long flag;
  if ((flag = IDAInit(mem, res, 0.0, yy, yp))) fail("IDAInit", flag);
  if ((flag = IDASStolerances(mem, tol, tol))) fail("IDASStolerances", flag);
  if ((flag = IDASetMaxNumSteps(mem, 10000000))) fail("IDASetMaxNumSteps", flag);
  if ((flag = IDASetStopTime(mem, t_end))) fail("IDASetStopTime", flag);
  return mem;
}

/* Free what a driver made. */
static void ida_finish(void *mem, SUNLinearSolver ls, SUNMatrix a, N_Vector yy, N_Vector yp,
                       SUNContext ctx) {
  IDAFree(&mem);
  SUNLinSolFree(ls);
  SUNMatDestroy(a);
  N_VDestroy(yy);
  N_VDestroy(yp);
  SUNContext_Free(&ctx);
}

#endif
