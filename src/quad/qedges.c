/* Edge infos of the quadtree (STUB; to be replaced). */
#include "quad/quad.h"
