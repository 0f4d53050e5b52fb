/* Defects of input surfaces (placeholder, being written). */
#ifndef MX_SURFACE_DEFECTS_H
#define MX_SURFACE_DEFECTS_H
#endif
