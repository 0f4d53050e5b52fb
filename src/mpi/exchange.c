/* All-to-all exchange of fixed-size records (src/mpi/exchange.h). */
#include "mpi/exchange.h"

#include "base/common.h"

#include <limits.h>

int mx_mpi_agree(MPI_Comm comm, int st) {
  int all = st;
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, comm);
  return all;
}

int mx_exchange(MPI_Comm comm, int st, size_t size, const void *send, const int *scount,
                void **recv, int **rcount_out, int **rdispl_out, long long *sent,
                long long *largest) {
  int R;
  MPI_Comm_size(comm, &R);
  int *sdispl = mx_alloc((size_t)(R + 1) * sizeof(int));
  int *rcount = mx_alloc((size_t)(R + 1) * sizeof(int));
  int *rdispl = mx_alloc((size_t)(R + 1) * sizeof(int));
  int all;
  if (!st && !(sdispl && rcount && rdispl)) st = MX_ENOMEM;
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, comm);
  *recv = NULL;
  *rcount_out = *rdispl_out = NULL;
  if (!all) {
    MPI_Alltoall(scount, 1, MPI_INT, rcount, 1, MPI_INT, comm);
    long long ns = 0, nr = 0;
    for (int r = 0; r < R; r++) {
      sdispl[r] = (int)ns;
      rdispl[r] = (int)nr;
      ns += scount[r];
      nr += rcount[r];
      const long long bytes = (long long)scount[r] * (long long)size;
      if (bytes > *largest) *largest = bytes;
    }
    *sent += ns * (long long)size;
    /* displacements are ints, counted in records */
    st = ns > INT_MAX || nr > INT_MAX ? MX_ENOMEM : MX_OK;
    if (!st) {
      *recv = mx_alloc(((size_t)nr + 1) * size);
      st = *recv ? MX_OK : MX_ENOMEM;
    }
    MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, comm);
  }
  if (!all) {
    MPI_Datatype rec;
    MPI_Type_contiguous((int)size, MPI_BYTE, &rec);
    MPI_Type_commit(&rec);
    MPI_Alltoallv(send, scount, sdispl, rec, *recv, rcount, rdispl, rec, comm);
    MPI_Type_free(&rec);
  }
  mx_free(sdispl);
  if (all) {
    mx_free(rcount);
    mx_free(rdispl);
    mx_free(*recv);
    *recv = NULL;
    return all;
  }
  *rcount_out = rcount;
  *rdispl_out = rdispl;
  return MX_OK;
}
