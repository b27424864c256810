C     Stand-ins for the R print/exit routines deTestSet's mebdfi.f calls.
      SUBROUTINE REXIT(S)
      CHARACTER*(*) S
      WRITE(6,*) 'REXIT: ', S
      STOP 1
      END
      SUBROUTINE RPRINT(S)
      CHARACTER*(*) S
      WRITE(6,*) S
      END
      SUBROUTINE RPRINTI1(S,I)
      CHARACTER*(*) S
      WRITE(6,*) S, I
      END
      SUBROUTINE RPRINTD1(S,D)
      CHARACTER*(*) S
      DOUBLE PRECISION D
      WRITE(6,*) S, D
      END
      SUBROUTINE RPRINTD2(S,D,E)
      CHARACTER*(*) S
      DOUBLE PRECISION D,E
      WRITE(6,*) S, D, E
      END
