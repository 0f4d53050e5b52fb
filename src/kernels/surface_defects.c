/* Defects of input surfaces (placeholder, being written). */
#include "kernels/surface_defects.h"
