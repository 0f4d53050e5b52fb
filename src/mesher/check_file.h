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

/* A 3D mesh's feature distances (verify/check.h, mx_check_feature_dist)
 * as check_file.c measured them. */
typedef struct {
  int measured;       /* 0: no features asked (no surface, angle 0, no file) */
  const char *file;   /* the polylines file, or NULL: found on the surface */
  double angle;       /* the surface's ridges (or the file's corners) at */
  double diagonal;    /* the surface's bounding box's, else the mesh
                       * boundary's: the distances are relative to it */
  double tol;         /* > 0: a distance above tol x diagonal is a defect */
  size_t off;         /* defects: the ridge and the corner distance, each
                       * above the tolerance (0 to 2) */
  mx_check_feature_dist d;
} mx_check_file_features;

/* A 3D mesh's report: one JSON object on one line, or the readable report
 * (surfs: the surface's files, nsurfs of them, 0 without; f: the feature
 * distances; the reading and checking times in seconds). The defects
 * counted are r's and f's. */
void mx_check_file_json(const mx_check_report *r, const mx_check_tags *t, uint64_t hash,
                        const mx_check_file_features *f);
void mx_check_file_text(const char *mesh, const char *const *surfs, int nsurfs,
                        const mx_check_report *r, const mx_check_tags *t, uint64_t hash,
                        const mx_check_file_features *f, double t_read, double t_check);
/* The same for a 2D mesh. */
void mx_check_file_json_2d(const mx_qmesh *M, const mx_check_file_2d *k);
void mx_check_file_text_2d(const char *mesh, const mx_qmesh *M, const mx_check_file_2d *k,
                           double t_read, double t_check);

#endif
