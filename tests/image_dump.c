/* Reads a label image (io/read_image.h) and prints what the reader made of
 * it, for tests/image_readers_test.py to compare against nibabel/numpy:
 *   format NAME
 *   dims NX NY NZ
 *   A a0 .. a11        (%.17g)
 *   spacing s0 s1 s2
 *   oblique 0|1
 *   rounded N
 *   sum S              (the sum of the labels, i fastest)
 *   wsum W             (the sum of label * (1 + v % 1000), v the voxel's index)
 *   at i j k L         (for each "i,j,k" argument after the path)
 * Exit 0, or the reader's status (its message on stderr). */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>

#include "io/read_image.h"

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: image_dump IMAGE [i,j,k ...]\n");
    return 2;
  }
  mx_label_image img;
  const int st = mx_read_label_image(argv[1], &img);
  if (st) return st;
  printf("format %s\n", img.format);
  printf("dims %" PRId64 " %" PRId64 " %" PRId64 "\n", img.nx, img.ny, img.nz);
  printf("A");
  for (int e = 0; e < 12; e++) printf(" %.17g", img.A[e]);
  printf("\nspacing %.17g %.17g %.17g\n", img.spacing[0], img.spacing[1], img.spacing[2]);
  printf("oblique %d\nrounded %zu\n", img.oblique, img.rounded);
  const size_t n = (size_t)img.nx * (size_t)img.ny * (size_t)img.nz;
  long long sum = 0, wsum = 0;
  for (size_t v = 0; v < n; v++) {
    sum += img.label[v];
    wsum += (long long)img.label[v] * (long long)(1 + v % 1000);
  }
  printf("sum %lld\nwsum %lld\n", sum, wsum);
  for (int a = 2; a < argc; a++) {
    long long i, j, k;
    if (sscanf(argv[a], "%lld,%lld,%lld", &i, &j, &k) != 3 || i < 0 || j < 0 || k < 0 ||
        i >= img.nx || j >= img.ny || k >= img.nz) {
      fprintf(stderr, "image_dump: bad voxel '%s'\n", argv[a]);
      mx_label_image_free(&img);
      return 2;
    }
    printf("at %lld %lld %lld %d\n", i, j, k,
           img.label[(size_t)i + (size_t)img.nx * ((size_t)j + (size_t)img.ny * (size_t)k)]);
  }
  mx_label_image_free(&img);
  return 0;
}
