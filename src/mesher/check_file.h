/* mx_check_file (include/mixoct.h, `mixoct check`) in two parts: reading
 * and checking (check_file.c) and printing the reports to stdout
 * (check_file_report.c). */
#ifndef MX_CHECK_FILE_H
#define MX_CHECK_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "quad/quad.h"
#include "verify/check.h"

/* A 2D mesh's check (check_file.c: the criteria of mesher2d's own). */
typedef struct {
  mx_qcheck_report c;
  mx_qquality q;
  const char *domain;   /* the polylines' file, or NULL */
  size_t unused_nodes;  /* informative, as in mesher2d: not a defect */
  size_t empty, topology_off, area_off, defects;
  double area_tol, dist_tol;
  int area_tol_auto;
} mx_check_file_2d;

/* A 3D mesh's report: one JSON object on one line, or the readable report
 * (surfs: the surface's files, nsurfs of them, 0 without; the reading and
 * checking times in seconds). */
void mx_check_file_json(const mx_check_report *r, const mx_check_tags *t, uint64_t hash);
void mx_check_file_text(const char *mesh, const char *const *surfs, int nsurfs,
                        const mx_check_report *r, const mx_check_tags *t, uint64_t hash,
                        double t_read, double t_check);
/* The same for a 2D mesh. */
void mx_check_file_json_2d(const mx_qmesh *M, const mx_check_file_2d *k);
void mx_check_file_text_2d(const char *mesh, const mx_qmesh *M, const mx_check_file_2d *k,
                           double t_read, double t_check);

#endif
