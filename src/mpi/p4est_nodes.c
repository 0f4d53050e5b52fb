/* Shared nodes of the distributed mesh: collected, agreed on, numbered
 * (src/mpi/p4est_nodes.h). */
#include "mpi/p4est_nodes.h"

#include "base/common.h"
#include "mpi/exchange.h"
#include "soa/mesh.h"
#include "base/scan.h"

#include <inttypes.h>
#include <string.h>

/* One node as sent to another rank: its lattice key, position, and its
 * state (agreement) or global number (numbering). */
typedef struct {
  uint64_t key;
  double x[3];
  uint64_t value;
} node_rec;

void mx_shared_free(mx_shared *sh) {
  mx_free(sh->peer);
  mx_free(sh->key);
  mx_free(sh->xyz);
  mx_free(sh->state);
  memset(sh, 0, sizeof *sh);
}

int mx_shared_collect(const mx_mesh *M, const uint8_t *states, const uint8_t *core,
                      const int32_t *leaf_owner, int rank, mx_shared *sh) {
  memset(sh, 0, sizeof *sh);
  uint8_t *used = mx_calloc(M->nnodes + 1);
  if (!used) return MX_ENOMEM;
  size_t npairs = 0;
  for (size_t c = 0; c < M->ncells; c++)
    if (core[c])
      for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) used[M->conn[8 * c + k]] = 1;
  for (size_t c = 0; c < M->ncells; c++)
    if (!core[c])
      for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) npairs += used[M->conn[8 * c + k]];
  /* (peer, node) pairs, unique */
  uint64_t *pair = mx_alloc((npairs + 1) * sizeof *pair);
  int st = pair ? MX_OK : MX_ENOMEM;
  size_t n = 0;
  for (size_t c = 0; !st && c < M->ncells; c++) {
    if (core[c]) continue;
    const int32_t q = leaf_owner[M->leaf[c]];
    if (q == rank) continue; /* cannot be: a non-core leaf is another rank's */
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (used[v]) pair[n++] = (uint64_t)(uint32_t)q << 32 | v;
    }
  }
  mx_free(used);
  if (!st) n = mx_sort_unique_u64(pair, n, &st);
  if (!st) {
    sh->peer = mx_alloc((n + 1) * sizeof *sh->peer);
    sh->key = mx_alloc((n + 1) * sizeof *sh->key);
    sh->xyz = mx_alloc((3 * n + 1) * sizeof *sh->xyz);
    sh->state = mx_alloc(n + 1);
    if (!sh->peer || !sh->key || !sh->xyz || !sh->state) st = MX_ENOMEM;
  }
  uint32_t *perm = NULL, *node = NULL;
  if (!st) {
    perm = mx_alloc((n + 1) * sizeof *perm);
    node = mx_alloc((n + 1) * sizeof *node);
    if (!perm || !node) st = MX_ENOMEM;
  }
  if (!st) {
    for (size_t i = 0; i < n; i++) {
      sh->peer[i] = (int32_t)(pair[i] >> 32);
      node[i] = (uint32_t)pair[i];
      sh->key[i] = M->nkey[node[i]];
      sh->unkeyed += sh->key[i] == MX_NKEY_NONE;
    }
    /* by key within each peer's group */
    for (size_t a = 0; !st && a < n;) {
      size_t b = a;
      while (b < n && sh->peer[b] == sh->peer[a]) b++;
      for (size_t i = a; i < b; i++) perm[i - a] = node[i];
      st = mx_sort_u64(sh->key + a, perm, b - a);
      for (size_t i = a; !st && i < b; i++) {
        const uint32_t v = perm[i - a];
        memcpy(sh->xyz + 3 * i, M->xyz + 3 * (size_t)v, 3 * sizeof *sh->xyz);
        sh->state[i] = states[v];
      }
      a = b;
    }
  }
  sh->n = n;
  mx_free(pair);
  mx_free(perm);
  mx_free(node);
  return st;
}

static int exchange(const mx_p4est_octree *P, mx_p4est_mesh *D, int st, const node_rec *send,
                    const int *scount, node_rec **recv, int **rcount, int **rdispl) {
  void *r = NULL;
  st = mx_exchange(P->comm, st, sizeof *send, send, scount, &r, rcount, rdispl, &D->sent_bytes,
                   &D->largest_message);
  *recv = r;
  return st;
}

static int same_rec(const node_rec *a, const node_rec *b) {
  return a->key == b->key && memcmp(a->x, b->x, sizeof a->x) == 0 && a->value == b->value;
}

int mx_shared_agree(const mx_p4est_octree *P, mx_p4est_mesh *D, const mx_shared *sh, int last,
                    const char *inputs, size_t *differ) {
  const int R = P->size;
  *differ = 0;
  node_rec *send = mx_alloc((sh->n + 1) * sizeof *send);
  int *scount = mx_calloc((size_t)(R + 1) * sizeof(int));
  int st = send && scount ? MX_OK : MX_ENOMEM;
  for (size_t i = 0; !st && i < sh->n; i++) {
    send[i].key = sh->key[i];
    memcpy(send[i].x, sh->xyz + 3 * i, sizeof send[i].x);
    send[i].value = sh->state[i];
    scount[sh->peer[i]]++;
  }
  node_rec *recv = NULL;
  int *rcount = NULL, *rdispl = NULL;
  st = exchange(P, D, st, send, scount, &recv, &rcount, &rdispl);
  /* walk each peer's list and ours, both sorted by key */
  size_t bad = sh->unkeyed;
  double first[3] = {0, 0, 0};
  int have_first = 0;
  if (!st) {
    size_t i = 0;
    for (int q = 0; q < R; q++) {
      const node_rec *a = send + i, *b = recv + rdispl[q];
      const size_t na = (size_t)scount[q], nb = (size_t)rcount[q];
      size_t x = 0, y = 0;
      while (x < na || y < nb) {
        const node_rec *d = NULL;
        if (y == nb || (x < na && a[x].key < b[y].key)) {
          d = a + x++;
        } else if (x == na || b[y].key < a[x].key) {
          d = b + y++;
        } else {
          if (!same_rec(a + x, b + y)) d = a + x;
          x++;
          y++;
        }
        if (d) {
          if (!have_first) memcpy(first, d->x, sizeof first);
          have_first = 1;
          bad++;
        }
      }
      i += na;
    }
  }
  /* the lowest rank with a difference names its first one */
  unsigned long long b = bad, gb = 0;
  int who = bad ? P->rank : P->size, gwho = who;
  if (!st) {
    MPI_Allreduce(&b, &gb, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, P->comm);
    MPI_Allreduce(&who, &gwho, 1, MPI_INT, MPI_MIN, P->comm);
    MPI_Bcast(first, 3, MPI_DOUBLE, gwho < P->size ? gwho : 0, P->comm);
    *differ = (size_t)gb;
    if (gb && last) {
      mx_error(inputs, 0, "%llu node(s) on the partition boundary came out differently on the "
                        "ranks sharing them, after %d halo rings; the first near (%.17g, "
                        "%.17g, %.17g) (rank %d): the distributed mesh would not conform",
               gb, D->rings, first[0], first[1], first[2], gwho);
      st = MX_EINVALID;
    }
  }
  mx_free(send);
  mx_free(scount);
  mx_free(recv);
  mx_free(rcount);
  mx_free(rdispl);
  return st;
}

int mx_shared_number(const mx_p4est_octree *P, mx_p4est_mesh *D, const mx_shared *sh) {
  const mx_mesh *M = &D->M;
  const size_t nn = M->nnodes;
  mx_free(D->gid);
  mx_free(D->owned);
  D->gid = mx_alloc((nn + 1) * sizeof *D->gid);
  D->owned = mx_alloc(nn + 1);
  int32_t *owner = mx_alloc((nn + 1) * sizeof *owner);
  uint64_t *skey = mx_alloc((nn + 1) * sizeof *skey);
  uint32_t *sidx = mx_alloc((nn + 1) * sizeof *sidx);
  uint32_t *at = mx_alloc((sh->n + 1) * sizeof *at);
  node_rec *send = mx_alloc((sh->n + 1) * sizeof *send);
  int *scount = mx_calloc((size_t)(P->size + 1) * sizeof(int));
  int st = D->gid && D->owned && owner && skey && sidx && at && send && scount ? MX_OK
                                                                              : MX_ENOMEM;
  /* the shared keys among this rank's nodes */
  size_t lost = 0;
  if (!st) {
    for (size_t v = 0; v < nn; v++) {
      skey[v] = M->nkey[v];
      sidx[v] = (uint32_t)v;
      owner[v] = P->rank;
    }
    st = mx_sort_u64(skey, sidx, nn);
  }
  for (size_t i = 0; !st && i < sh->n; i++) {
    const uint32_t j = sh->key[i] == MX_NKEY_NONE ? UINT32_MAX : mx_find_u64(skey, nn, sh->key[i]);
    at[i] = j == UINT32_MAX ? UINT32_MAX : sidx[j];
    if (at[i] == UINT32_MAX) {
      lost++;
      continue;
    }
    if (sh->peer[i] < owner[at[i]]) owner[at[i]] = sh->peer[i];
  }
  MPI_Allreduce(MPI_IN_PLACE, &st, 1, MPI_INT, MPI_MAX, P->comm);
  if (!st) {
    uint64_t nown = 0;
    for (size_t v = 0; v < nn; v++) nown += owner[v] == P->rank;
    uint64_t first = 0;
    MPI_Exscan(&nown, &first, 1, MPI_UINT64_T, MPI_SUM, P->comm);
    if (P->rank == 0) first = 0; /* MPI_Exscan leaves rank 0's undefined */
    D->first_owned = first;
    D->nowned = nown;
    uint64_t g = first;
    for (size_t v = 0; v < nn; v++) {
      D->owned[v] = owner[v] == P->rank;
      D->gid[v] = D->owned[v] ? g++ : UINT64_MAX;
    }
    /* the owned shared nodes' numbers, to the peers */
    size_t k = 0;
    for (size_t i = 0; i < sh->n; i++) {
      if (at[i] == UINT32_MAX || owner[at[i]] != P->rank) continue;
      send[k].key = sh->key[i];
      memcpy(send[k].x, M->xyz + 3 * (size_t)at[i], sizeof send[k].x);
      send[k++].value = D->gid[at[i]];
      scount[sh->peer[i]]++;
    }
  }
  node_rec *recv = NULL;
  int *rcount = NULL, *rdispl = NULL;
  st = exchange(P, D, st, send, scount, &recv, &rcount, &rdispl);
  size_t missing = lost;
  if (!st) {
    for (int q = 0; q < P->size; q++)
      for (int i = 0; i < rcount[q]; i++) {
        const node_rec *r = recv + rdispl[q] + i;
        const uint32_t j = mx_find_u64(skey, nn, r->key);
        if (j == UINT32_MAX || owner[sidx[j]] != q) {
          missing++;
          continue;
        }
        D->gid[sidx[j]] = r->value;
      }
    for (size_t v = 0; v < nn; v++) missing += D->gid[v] == UINT64_MAX;
  }
  unsigned long long m = missing, gm = 0;
  if (!st) {
    MPI_Allreduce(&m, &gm, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, P->comm);
    if (gm) {
      mx_error(NULL, 0, "internal: %llu shared node(s) got no global number", gm);
      st = MX_EINTERNAL;
    }
  }
  /* nodes of this rank another rank's elements use too */
  size_t nshared = 0;
  if (!st) {
    uint8_t *mark = mx_calloc(nn + 1);
    if (mark) {
      for (size_t i = 0; i < sh->n; i++)
        if (at[i] != UINT32_MAX && !mark[at[i]]) {
          mark[at[i]] = 1;
          nshared++;
        }
    }
    mx_free(mark);
  }
  D->shared_nodes = nshared;
  mx_free(owner);
  mx_free(skey);
  mx_free(sidx);
  mx_free(at);
  mx_free(send);
  mx_free(scount);
  mx_free(recv);
  mx_free(rcount);
  mx_free(rdispl);
  return st;
}
