/* Recursive balance of the quadtree, the baseline (STUB; to be replaced). */
#include "quad/quad.h"
