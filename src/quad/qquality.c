/* 2D cell quality (STUB; to be replaced). */
#include <string.h>

#include "common.h"
#include "quad/quad.h"

double mx_qcell_sj(const mx_qmesh *M, size_t c) { (void)M; (void)c; return 0.0; }
double mx_qcell_min_angle(const mx_qmesh *M, size_t c) { (void)M; (void)c; return 0.0; }
void mx_qquality_measure(const mx_qmesh *M, mx_qquality *q) { (void)M; memset(q, 0, sizeof *q); }
