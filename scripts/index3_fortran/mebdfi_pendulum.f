C     MEBDFI on the pendulum (S01, t = 20, exact (1,0,0,0,0)), index 3 as
C     written, NIND=(2,2,1). Usage: pendm TOL (rtol = atol = h0 = TOL).
      PROGRAM PENDM
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      PARAMETER (N=5, LWORK=40+N*(34+2*N), LIWORK=N+14)
      DIMENSION Y(N),YP(N),WORK(LWORK),IWORK(LIWORK),RPAR(1),IPAR(1)
      DIMENSION MBND(4),RTOL(1),ATOL(1)
      CHARACTER*32 ARG
      EXTERNAL RP,PDUM
      CALL GETARG(1,ARG)
      READ(ARG,*) TOL
      G=13.7503716373294544D0
      Y=0D0
      Y(1)=1D0
      YP=0D0
      YP(4)=-G
      WORK=0D0
      IWORK=0
      IWORK(1)=2
      IWORK(2)=2
      IWORK(3)=1
      IWORK(14)=1000000
      T=0D0
      TEND=20D0
      H=TOL
      RTOL(1)=TOL
      ATOL(1)=TOL
      IDID=1
      IERR=0
      DO K=1,1000000
         CALL MEBDFI(N,T,H,Y,YP,TEND,TEND,22,IDID,LWORK,WORK,LIWORK,
     &     IWORK,MBND,7,2,RTOL,ATOL,RPAR,IPAR,PDUM,RP,IERR)
         IF (IDID.LT.0) GOTO 10
         IF (T.GE.TEND) GOTO 10
         IDID=0
      END DO
 10   CONTINUE
      E=MAX(ABS(Y(1)-1D0),ABS(Y(2)),ABS(Y(3)),ABS(Y(4)),ABS(Y(5)))
      EQ=MAX(ABS(Y(1)-1D0),ABS(Y(2)))
      EV=MAX(ABS(Y(3)),ABS(Y(4)))
      WRITE(6,'(A,1PE8.1,A,I3,A,0PF6.2,A,F6.2,A,F6.2,A,F6.2,A,I7,A,I7)')
     & 'tol ',TOL,' idid ',IDID,' scd(all) ',-LOG10(E),
     & ' scd(q) ',-LOG10(EQ),' scd(v) ',-LOG10(EV),
     & ' scd(lam) ',-LOG10(ABS(Y(5))),
     & ' steps ',IWORK(5),' failed ',IWORK(6)
      END
      SUBROUTINE RP(T,Y,YP,CJ,DELTA,IERR,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION Y(5),YP(5),DELTA(5)
      G=13.7503716373294544D0
      DELTA(1)=YP(1)-Y(3)
      DELTA(2)=YP(2)-Y(4)
      DELTA(3)=YP(3)+2D0*Y(1)*Y(5)
      DELTA(4)=YP(4)+2D0*Y(2)*Y(5)+G
      DELTA(5)=-(Y(1)**2+Y(2)**2-1D0)
      END
      SUBROUTINE PDUM(T,Y,YP,PD,CJ,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      END
