/* Reading the runtime's data file (see mace_data.h). */
#include "mace_data.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "mace_model.h"

static const char MAGIC[8] = {'M', 'A', 'C', 'E', 'F', 'M', 'U', '1'};

static int read_u32(const unsigned char *b, size_t size, size_t *pos, uint32_t *v) {
    if (size - *pos < 4 || *pos > size) return -1;
    *v = (uint32_t)b[*pos] | (uint32_t)b[*pos + 1] << 8 | (uint32_t)b[*pos + 2] << 16 | (uint32_t)b[*pos + 3] << 24;
    *pos += 4;
    return 0;
}

static int read_u64(const unsigned char *b, size_t size, size_t *pos, uint64_t *v) {
    uint32_t lo, hi;
    if (read_u32(b, size, pos, &lo) || read_u32(b, size, pos, &hi)) return -1;
    *v = (uint64_t)hi << 32 | lo;
    return 0;
}

static int host_is_little_endian(void) {
    const uint16_t one = 1;
    return *(const unsigned char *)&one == 1;
}

int mace_resource_read(MaceFile *f, const char *resource_dir, const MaceAlloc *al, char *path, size_t path_size,
                       char *err) {
    size_t len = strlen(resource_dir);
    const char *sep = (len && (resource_dir[len - 1] == '/' || resource_dir[len - 1] == '\\')) ? "" : "/";
    if (len + sizeof(MACE_DATA_FILE) + 2 > path_size) {
        snprintf(err, MACE_ERR_LEN, "resource path too long");
        return -1;
    }
    snprintf(path, path_size, "%s%s%s", resource_dir, sep, MACE_DATA_FILE);
    return mace_file_read(f, path, al, err);
}

int mace_file_read(MaceFile *f, const char *path, const MaceAlloc *al, char *err) {
    FILE *fp;
    long size;
    size_t pos = 8, k, names_size = 0;
    uint32_t version, count;
    memset(f, 0, sizeof(*f));
    if (!host_is_little_endian()) {
        snprintf(err, MACE_ERR_LEN, "this runtime reads its data on little-endian machines only");
        return -1;
    }
    fp = fopen(path, "rb");
    if (!fp) {
        snprintf(err, MACE_ERR_LEN, "cannot open the model data %s", path);
        return -1;
    }
    if (fseek(fp, 0, SEEK_END) != 0 || (size = ftell(fp)) < 16 || fseek(fp, 0, SEEK_SET) != 0) {
        fclose(fp);
        snprintf(err, MACE_ERR_LEN, "%.900s: not a mace-fmu model data file (too short)", path);
        return -1;
    }
    f->size = (size_t)size;
    f->bytes = (unsigned char *)al->calloc(f->size, 1);
    if (!f->bytes || fread(f->bytes, 1, f->size, fp) != f->size) {
        fclose(fp);
        snprintf(err, MACE_ERR_LEN, "%.900s: cannot read %ld bytes", path, size);
        mace_file_free(f, al);
        return -1;
    }
    fclose(fp);
    if (memcmp(f->bytes, MAGIC, 8) != 0 || read_u32(f->bytes, f->size, &pos, &version) ||
        read_u32(f->bytes, f->size, &pos, &count) || version != 1 || count > 100000) {
        snprintf(err, MACE_ERR_LEN, "%.900s: not a mace-fmu model data file of format 1", path);
        mace_file_free(f, al);
        return -1;
    }
    f->entries = (MaceEntry *)al->calloc(count ? count : 1, sizeof(MaceEntry));
    names_size = f->size + count;  /* every name is shorter than the file */
    f->names = (char *)al->calloc(names_size, 1);
    if (!f->entries || !f->names) {
        snprintf(err, MACE_ERR_LEN, "%.900s: out of memory", path);
        mace_file_free(f, al);
        return -1;
    }
    {
        char *name_out = f->names;
        for (k = 0; k < count; k++) {
            MaceEntry *e = &f->entries[k];
            uint32_t len, type, ndim, d;
            uint64_t items = 1, nbytes;
            if (read_u32(f->bytes, f->size, &pos, &len) || len > f->size - pos) goto corrupt;
            memcpy(name_out, f->bytes + pos, len);
            name_out[len] = '\0';
            e->name = name_out;
            name_out += len + 1;
            pos += len;
            if (read_u32(f->bytes, f->size, &pos, &type) || read_u32(f->bytes, f->size, &pos, &ndim) || ndim > 4 ||
                type < MACE_F64 || type > MACE_TEXT)
                goto corrupt;
            e->type = type;
            e->ndim = ndim;
            for (d = 0; d < ndim; d++) {
                uint64_t v;
                if (read_u64(f->bytes, f->size, &pos, &v) || v > f->size) goto corrupt;
                e->dims[d] = (size_t)v;
                items *= v;
                if (items > f->size) goto corrupt;
            }
            if (type == MACE_TEXT) {
                if (read_u64(f->bytes, f->size, &pos, &nbytes)) goto corrupt;
            } else {
                nbytes = items * 8;
            }
            pos += (8 - pos % 8) % 8;
            if (pos > f->size || nbytes > f->size - pos) goto corrupt;
            e->data = f->bytes + pos;
            e->nbytes = (size_t)nbytes;
            pos += (size_t)nbytes;
            pos += (8 - pos % 8) % 8;
            f->n = k + 1;
            continue;
        corrupt:
            snprintf(err, MACE_ERR_LEN, "%.900s: corrupt model data at entry %lu", path, (unsigned long)k);
            mace_file_free(f, al);
            return -1;
        }
    }
    return 0;
}

void mace_file_free(MaceFile *f, const MaceAlloc *al) {
    al->free(f->bytes);
    al->free(f->entries);
    al->free(f->names);
    memset(f, 0, sizeof(*f));
}

static const MaceEntry *find(const MaceFile *f, const char *name) {
    size_t k;
    for (k = 0; k < f->n; k++)
        if (strcmp(f->entries[k].name, name) == 0) return &f->entries[k];
    return NULL;
}

int mace_file_has(const MaceFile *f, const char *name) { return find(f, name) != NULL; }

const void *mace_file_get(const MaceFile *f, const char *name, unsigned type, size_t ndim, const size_t *dims,
                          char *err) {
    const MaceEntry *e = find(f, name);
    size_t d;
    if (!e) {
        snprintf(err, MACE_ERR_LEN, "model data: entry '%s' is missing", name);
        return NULL;
    }
    if (e->type != type || e->ndim != ndim) {
        snprintf(err, MACE_ERR_LEN, "model data: entry '%s' has type %u and %lu dimensions, expected %u and %lu", name,
                 e->type, (unsigned long)e->ndim, type, (unsigned long)ndim);
        return NULL;
    }
    for (d = 0; d < ndim; d++) {
        if (e->dims[d] != dims[d]) {
            snprintf(err, MACE_ERR_LEN, "model data: entry '%s' has %lu items along axis %lu, expected %lu", name,
                     (unsigned long)e->dims[d], (unsigned long)d, (unsigned long)dims[d]);
            return NULL;
        }
    }
    return e->data;
}

int mace_file_strings(const MaceFile *f, const char *name, size_t n, const char **out, char *err) {
    const MaceEntry *e = find(f, name);
    const char *p, *end;
    size_t k;
    if (!e || e->type != MACE_TEXT || e->ndim != 1 || e->dims[0] != n) {
        snprintf(err, MACE_ERR_LEN, "model data: text entry '%s' with %lu strings is missing", name, (unsigned long)n);
        return -1;
    }
    p = (const char *)e->data;
    end = p + e->nbytes;
    for (k = 0; k < n; k++) {
        const char *nul = (const char *)memchr(p, '\0', (size_t)(end - p));
        if (!nul) {
            snprintf(err, MACE_ERR_LEN, "model data: text entry '%s' is truncated", name);
            return -1;
        }
        out[k] = p;
        p = nul + 1;
    }
    return 0;
}
