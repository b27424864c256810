C     MEBDFI (Abdulla & Cash, deTestSet's copy) on the car axis, index 3
C     as written, NIND = (4, 4, 2). Usage: carm TOL (rtol = atol = h0 = TOL)
      PROGRAM CARM
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      PARAMETER (N=10, LWORK=40+N*(34+2*N), LIWORK=N+14)
      DIMENSION Y(N),YP(N),F(N),WORK(LWORK),IWORK(LIWORK),RPAR(1),IPAR(1)
      DIMENSION YREF(N),MBND(4),RTOL(1),ATOL(1)
      CHARACTER*32 ARG
      EXTERNAL RCAR,PDUM
      CALL GETARG(1,ARG)
      READ(ARG,*) TOL
      YREF(1)= 0.4934557842755629D-01
      YREF(2)= 0.4969894602303324D+00
      YREF(3)= 0.1041742524885400D+01
      YREF(4)= 0.3739110272652214D+00
      YREF(5)=-0.7705836840321485D-01
      YREF(6)= 0.7446866596327776D-02
      YREF(7)= 0.1755681574942899D-01
      YREF(8)= 0.7703410437794031D+00
      YREF(9)=-0.4736886750784630D-02
      YREF(10)=-0.1104680411345730D-02
      Y(1)=0D0
      Y(2)=0.5D0
      Y(3)=1D0
      Y(4)=0.5D0
      Y(5)=-0.5D0
      Y(6)=0D0
      Y(7)=-0.5D0
      Y(8)=0D0
      Y(9)=0D0
      Y(10)=0D0
      CALL FCAR(N,0D0,Y,F)
      AK=10D0*1D-4/2D0
      DO I=1,4
         YP(I)=Y(I+4)
         YP(I+4)=F(I+4)/AK
      END DO
      YP(9)=0D0
      YP(10)=0D0
      DO I=1,LWORK
         WORK(I)=0D0
      END DO
      DO I=1,LIWORK
         IWORK(I)=0
      END DO
      IWORK(1)=4
      IWORK(2)=4
      IWORK(3)=2
      IWORK(14)=1000000
      T=0D0
      TEND=3D0
      H=TOL
      RTOL(1)=TOL
      ATOL(1)=TOL
      IDID=1
      IERR=0
      DO K=1,100000
         CALL MEBDFI(N,T,H,Y,YP,TEND,TEND,22,IDID,LWORK,WORK,LIWORK,
     &     IWORK,MBND,7,2,RTOL,ATOL,RPAR,IPAR,PDUM,RCAR,IERR)
         IF (IDID.LT.0) GOTO 10
         IF (T.GE.TEND) GOTO 10
         IDID=0
      END DO
 10   CONTINUE
      E8=0D0
      E10=0D0
      EP=0D0
      DO I=1,N
         E=ABS(Y(I)-YREF(I))/ABS(YREF(I))
         IF (I.LE.8) E8=MAX(E8,E)
         IF (I.LE.4) EP=MAX(EP,E)
         E10=MAX(E10,E)
      END DO
      WRITE(6,'(A,1PE8.1,A,I3,A,0PF6.2,A,F6.2,A,F6.2,A,I7,A,I7)')
     & 'tol ',TOL,' idid ',IDID,' scd(q,v) ',-LOG10(E8),
     & ' scd(q) ',-LOG10(EP),' scd(all) ',-LOG10(E10),
     & ' steps ',IWORK(5),' failed ',IWORK(6)
      END
      SUBROUTINE RCAR(T,Y,YP,CJ,DELTA,IERR,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION Y(10),YP(10),DELTA(10),F(10)
      CALL FCAR(10,T,Y,F)
      AK=10D0*1D-4/2D0
      DO I=1,4
         DELTA(I)=YP(I)-F(I)
         DELTA(I+4)=AK*YP(I+4)-F(I+4)
      END DO
      DELTA(9)=-F(9)
      DELTA(10)=-F(10)
      END
      SUBROUTINE PDUM(T,Y,YP,PD,CJ,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      END
      SUBROUTINE FCAR(N,T,Y,F,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION Y(N),F(N)
      EPS=1D-2
      AM=10D0
      AL=1D0
      AL0=0.5D0
      R=0.1D0
      W=10D0
      G=1D0
      YB=R*SIN(W*T)
      XB=SQRT(AL*AL-YB*YB)
      XL=Y(1)
      YL=Y(2)
      XR=Y(3)
      YR=Y(4)
      AL1=Y(9)
      AL2=Y(10)
      ALL=SQRT(XL**2+YL**2)
      ALR=SQRT((XR-XB)**2+(YR-YB)**2)
      AK=AM*EPS*EPS/2D0
      F(1)=Y(5)
      F(2)=Y(6)
      F(3)=Y(7)
      F(4)=Y(8)
      F(5)=(AL0-ALL)*XL/ALL+AL1*XB+2D0*AL2*(XL-XR)
      F(6)=(AL0-ALL)*YL/ALL+AL1*YB+2D0*AL2*(YL-YR)-AK*G
      F(7)=(AL0-ALR)*(XR-XB)/ALR-2D0*AL2*(XL-XR)
      F(8)=(AL0-ALR)*(YR-YB)/ALR-2D0*AL2*(YL-YR)-AK*G
      F(9)=XB*XL+YB*YL
      F(10)=(XL-XR)**2+(YL-YR)**2-AL*AL
      END
