/* All-to-all exchange of fixed-size records (the distributed mesh's node
 * lists and halo queries), and the agreement on a status. */
#ifndef MX_MPI_EXCHANGE_H
#define MX_MPI_EXCHANGE_H

#include <mpi.h>
#include <stddef.h>

/* The largest status over the ranks of comm (MX_OK when every rank's is):
 * a failure on one rank becomes everyone's. Collective. */
int mx_mpi_agree(MPI_Comm comm, int st);

/* Sends send[] (records of `size` bytes grouped by destination rank,
 * scount[r] to rank r) and receives *recv (mx_alloc; rcount and rdispl,
 * mx_alloc, per source rank, in records). st: this rank's status so far: a
 * failure anywhere and nothing is sent, every rank returns it (the outputs
 * NULL). *sent (bytes) is increased, *largest (bytes to one rank) raised. */
int mx_exchange(MPI_Comm comm, int st, size_t size, const void *send, const int *scount,
                void **recv, int **rcount, int **rdispl, long long *sent, long long *largest);

#endif
