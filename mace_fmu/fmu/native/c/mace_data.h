/* Reading the runtime's data file (layout: mace_fmu/fmu/native/resource.py). */
#ifndef MACE_DATA_H
#define MACE_DATA_H

#include <stddef.h>

#include "mace_linalg.h"

enum { MACE_F64 = 1, MACE_I64 = 2, MACE_TEXT = 3 };

typedef struct MaceEntry {
    const char *name;  /* NUL-terminated copy */
    unsigned type;
    size_t ndim;
    size_t dims[4];
    const void *data;  /* 8-byte aligned inside the file buffer */
    size_t nbytes;
} MaceEntry;

typedef struct MaceFile {
    unsigned char *bytes;
    size_t size;
    MaceEntry *entries;
    char *names;
    size_t n;
} MaceFile;

/* Reads and indexes the whole file; on failure the message names the file and what is wrong. */
int mace_file_read(MaceFile *f, const char *path, const MaceAlloc *al, char *err);
/* mace_file_read of resource_dir/MACE_DATA_FILE; the file's path goes into path (path_size bytes). */
int mace_resource_read(MaceFile *f, const char *resource_dir, const MaceAlloc *al, char *path, size_t path_size,
                       char *err);
void mace_file_free(MaceFile *f, const MaceAlloc *al);
/* 1 if the file has an entry `name` (an optional part of the data), else 0. */
int mace_file_has(const MaceFile *f, const char *name);
/* The entry `name` with this type and shape (ndim dims), or NULL and a message. */
const void *mace_file_get(const MaceFile *f, const char *name, unsigned type, size_t ndim, const size_t *dims,
                          char *err);
/* The n strings of a text entry into out[0..n-1] (pointers into the file buffer). */
int mace_file_strings(const MaceFile *f, const char *name, size_t n, const char **out, char *err);

#endif
