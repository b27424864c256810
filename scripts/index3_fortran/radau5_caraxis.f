C     RADAU5 (Hairer-Wanner, radau5.f) on the IVP Test Set car axis,
C     index 3 as written: NIND = (4, 4, 2). Written for dae's idx10
C     comparison. Usage: car TOL  (rtol = atol = h0 = TOL, Test Set style)
      PROGRAM CAR
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      PARAMETER (N=10, LWORK=N*(5*N+12)+20, LIWORK=3*N+20)
      DIMENSION Y(N),WORK(LWORK),IWORK(LIWORK),RPAR(1),IPAR(1)
      DIMENSION YREF(N)
      CHARACTER*32 ARG
      EXTERNAL FCAR,MCAR,SOLX,JDUM
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
      DO I=1,20
         IWORK(I)=0
         WORK(I)=0D0
      END DO
      IWORK(2)=1000000
      IWORK(5)=4
      IWORK(6)=4
      IWORK(7)=2
      X=0D0
      XEND=3D0
      H=TOL
      RTOL=TOL
      ATOL=TOL
      ML1=N
      MU1=N
      ML2=N
      MU2=N
      CALL RADAU5(N,FCAR,X,Y,XEND,H,RTOL,ATOL,0,JDUM,0,ML1,MU1,
     &   MCAR,1,ML2,MU2,SOLX,0,WORK,LWORK,IWORK,LIWORK,RPAR,IPAR,
     &   IDID)
C     scd as the scene: relative, positions and velocities (1..8);
C     and over all ten (the multipliers too)
      E8=0D0
      E10=0D0
      DO I=1,N
         E=ABS(Y(I)-YREF(I))/ABS(YREF(I))
         IF (I.LE.8) E8=MAX(E8,E)
         E10=MAX(E10,E)
      END DO
      EP=0D0
      DO I=1,4
         EP=MAX(EP,ABS(Y(I)-YREF(I))/ABS(YREF(I)))
      END DO
      WRITE(6,'(A,1PE8.1,A,I3,A,0PF6.2,A,F6.2,A,F6.2,A,I7,A,I7)')
     & 'tol ',TOL,' idid ',IDID,' scd(q,v) ',-LOG10(E8),
     & ' scd(q) ',-LOG10(EP),' scd(all) ',-LOG10(E10),
     & ' steps ',IWORK(16),' rejected ',IWORK(18)
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
      SUBROUTINE MCAR(N,AM,LMAS,RPAR,IPAR)
      IMPLICIT DOUBLE PRECISION (A-H,O-Z)
      DIMENSION AM(LMAS,N)
      DO J=1,N
         DO I=1,LMAS
            AM(I,J)=0D0
         END DO
      END DO
      AK=10D0*1D-4/2D0
      DO I=1,4
         AM(I,I)=1D0
      END DO
      DO I=5,8
         AM(I,I)=AK
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
