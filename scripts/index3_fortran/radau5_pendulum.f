C     RADAU5 on the pendulum (S01: g chosen for period 2, t = 20 is ten
C     periods, exact state (1,0,0,0,0)), index 3 as written, NIND=(2,2,1).
C     Usage: pend TOL (rtol = atol = h0 = TOL). scd absolute over all five.
      PROGRAM PEND
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      PARAMETER (N=5, LWORK=N*(5*N+12)+20, LIWORK=3*N+20)
      DIMENSION Y(N),WORK(LWORK),IWORK(LIWORK),RPAR(1),IPAR(1)
      CHARACTER*32 ARG
      EXTERNAL FP,MP,SOLX,JDUM
      CALL GETARG(1,ARG)
      READ(ARG,*) TOL
      Y(1)=1D0
      Y(2)=0D0
      Y(3)=0D0
      Y(4)=0D0
      Y(5)=0D0
      DO I=1,20
         IWORK(I)=0
         WORK(I)=0D0
      END DO
      IWORK(2)=1000000
      IWORK(5)=2
      IWORK(6)=2
      IWORK(7)=1
      X=0D0
      XEND=20D0
      H=TOL
      RTOL=TOL
      ATOL=TOL
      ML1=N
      MU1=N
      ML2=N
      MU2=N
      CALL RADAU5(N,FP,X,Y,XEND,H,RTOL,ATOL,0,JDUM,0,ML1,MU1,
     &   MP,1,ML2,MU2,SOLX,0,WORK,LWORK,IWORK,LIWORK,RPAR,IPAR,IDID)
      E=MAX(ABS(Y(1)-1D0),ABS(Y(2)),ABS(Y(3)),ABS(Y(4)),ABS(Y(5)))
      EQ=MAX(ABS(Y(1)-1D0),ABS(Y(2)))
      EV=MAX(ABS(Y(3)),ABS(Y(4)))
      WRITE(6,'(A,1PE8.1,A,I3,A,0PF6.2,A,F6.2,A,F6.2,A,F6.2,A,I7,A,I7)')
     & 'tol ',TOL,' idid ',IDID,' scd(all) ',-LOG10(E),
     & ' scd(q) ',-LOG10(EQ),' scd(v) ',-LOG10(EV),
     & ' scd(lam) ',-LOG10(ABS(Y(5))),
     & ' steps ',IWORK(16),' rejected ',IWORK(18)
      END
      SUBROUTINE FP(N,T,Y,F,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION Y(N),F(N)
      G=13.7503716373294544D0
      F(1)=Y(3)
      F(2)=Y(4)
      F(3)=-2D0*Y(1)*Y(5)
      F(4)=-2D0*Y(2)*Y(5)-G
      F(5)=Y(1)**2+Y(2)**2-1D0
      END
      SUBROUTINE MP(N,AM,LMAS,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION AM(LMAS,N)
      DO J=1,N
         DO I=1,LMAS
            AM(I,J)=0D0
         END DO
      END DO
      DO I=1,4
         AM(I,I)=1D0
      END DO
      END
      SUBROUTINE SOLX(NR,XOLD,X,Y,CONT,LRC,N,RPAR,IPAR,IRTRN)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION Y(N),CONT(LRC)
      END
      SUBROUTINE JDUM(N,X,Y,DFY,LDFY,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION Y(N),DFY(LDFY,N)
      END
