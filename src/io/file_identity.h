/* mixoct: whether two paths name one file, and the check of a run's files
 * before anything is read or written: no output may replace an input or
 * another output.
 *
 * Identity is the file's, not the spelling's: for files that exist, device
 * and inode (so "a.vtk", "./a.vtk", a hard link and a symbolic link to it are
 * one file); for files not yet written, the device and inode of the
 * directory they go to and their name in it. */
#ifndef MX_FILE_IDENTITY_H
#define MX_FILE_IDENTITY_H

/* How a run uses a file. The restart file written may replace the restart
 * file read (the re-meshing loop of the 2021 paper: it is read whole before
 * and written under a temporary name); nothing else may share a file with
 * an output. */
#include "mixoct.h" /* MX_FILE_*, mx_file_use, mx_check_file_uses */

/* A file's identity, to compare with paths later (the library remembers
 * the files a mesher read). */
typedef struct {
  unsigned long long dev, ino;
} mx_file_id;
/* 1 and *id filled when path names an existing file, else 0. */
int mx_file_id_of(const char *path, mx_file_id *id);

/* 1 when a and b name the same file (existing or to be written), else 0. */
int mx_same_file(const char *a, const char *b);

#endif
