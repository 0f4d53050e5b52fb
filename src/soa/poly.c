/* Freeing a set of polylines (soa/poly.h). */
#include "soa/poly.h"

#include <string.h>

#include "base/common.h"

void mx_poly_free(mx_poly *P) {
  mx_free(P->xy);
  mx_free(P->seg);
  mx_free(P->line);
  mx_free(P->holes);
  mx_free(P->path);
  memset(P, 0, sizeof *P);
}
