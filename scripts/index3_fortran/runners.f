C     The two reference codes called the same way for every problem of
C     scripts/index3_fortran.sh: rtol = atol = h0 = TOL (scalars), full
C     numerical Jacobian, NIND = (NI1, NI2, NI3), from T = 0 to TEND.
C     RADAU5 (Hairer & Wanner) on M y' = f(t, y): FCN, MAS as radau5.f.
      SUBROUTINE RUNR5(N,FCN,MAS,Y,TEND,TOL,NI1,NI2,NI3,IDID,NSTEP)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      PARAMETER (NMAX=27, LWORK=NMAX*(5*NMAX+12)+20, LIWORK=3*NMAX+20)
      DIMENSION Y(N),WORK(LWORK),IWORK(LIWORK),RPAR(1),IPAR(1)
      EXTERNAL FCN,MAS,SOLX,JDUM
      WORK=0D0
      IWORK=0
      IWORK(2)=1000000
      IWORK(5)=NI1
      IWORK(6)=NI2
      IWORK(7)=NI3
      T=0D0
      H=TOL
      RTOL=TOL
      ATOL=TOL
      ML1=N
      MU1=N
      ML2=N
      MU2=N
      CALL RADAU5(N,FCN,T,Y,TEND,H,RTOL,ATOL,0,JDUM,0,ML1,MU1,
     &   MAS,1,ML2,MU2,SOLX,0,WORK,LWORK,IWORK,LIWORK,RPAR,IPAR,IDID)
      NSTEP=IWORK(16)
      END
C     MEBDFI (Abdulla & Cash, deTestSet's copy) on G(t, y, y') = 0 in
C     DASPK's calling sequence RES(T,Y,YP,CJ,DELTA,IERR,RPAR,IPAR), with
C     the consistent derivative YP; returns the solution at TEND
C     (interpolated, as the Test Set's driver).
      SUBROUTINE RUNMB(N,RES,Y,YP,TEND,TOL,NI1,NI2,NI3,IDID,NSTEP)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      PARAMETER (NMAX=27, LWORK=40+NMAX*(34+2*NMAX), LIWORK=NMAX+14)
      DIMENSION Y(N),YP(N),WORK(LWORK),IWORK(LIWORK),RPAR(1),IPAR(1)
      DIMENSION MBND(4),RTOL(1),ATOL(1)
      EXTERNAL RES,PDUM
      WORK=0D0
      IWORK=0
      IWORK(1)=NI1
      IWORK(2)=NI2
      IWORK(3)=NI3
      IWORK(14)=1000000
      T=0D0
      H=TOL
      RTOL(1)=TOL
      ATOL(1)=TOL
      IDID=1
      IERR=0
      DO K=1,1000000
         CALL MEBDFI(N,T,H,Y,YP,TEND,TEND,22,IDID,LWORK,WORK,LIWORK,
     &     IWORK,MBND,7,2,RTOL,ATOL,RPAR,IPAR,PDUM,RES,IERR)
         IF (IDID.LT.0.OR.T.GE.TEND) GOTO 10
         IDID=0
      END DO
 10   NSTEP=IWORK(5)
      END
      SUBROUTINE SOLX(NR,XOLD,X,Y,CONT,LRC,N,RPAR,IPAR,IRTRN)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      END
      SUBROUTINE JDUM(N,X,Y,DFY,LDFY,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      END
      SUBROUTINE PDUM(T,Y,YP,PD,CJ,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      END
C     The largest relative error of Y(I1..I2) against YREF, as scd.
      DOUBLE PRECISION FUNCTION SCDREL(Y,YREF,I1,I2)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION Y(*),YREF(*)
      E=0D0
      DO I=I1,I2
         E=MAX(E,ABS(Y(I)-YREF(I))/ABS(YREF(I)))
      END DO
      SCDREL=-LOG10(E)
      END
C     One line of output: code, tolerance, return flag, scd, steps.
      SUBROUTINE REPORT(ICODE,TOL,IDID,SCD,NSTEP)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      CHARACTER*6 NAME(2)
      DATA NAME/'RADAU5','MEBDFI'/
      WRITE(6,'(A6,A,1PE8.1,A,I3,A,0PF6.2,A,I7)') NAME(ICODE),
     & ' tol ',TOL,' idid ',IDID,' scd ',SCD,' steps ',NSTEP
      END
