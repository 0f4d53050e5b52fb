/* The quadtree (STUB; to be replaced). */
#include <string.h>

#include "common.h"
#include "quad/quad.h"

void mx_qtree_free(mx_qtree *T) { memset(T, 0, sizeof *T); }
int mx_qtree_leaves(const mx_qtree *T, uint32_t **leaves, size_t *n) {
  (void)T; *leaves = NULL; *n = 0;
  return MX_EINTERNAL;
}
size_t mx_qtree_unbalanced(const mx_qtree *T) { (void)T; return 0; }
