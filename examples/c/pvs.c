/*
 * pvs.c: vocc's C ABI as an engine uses it. Reads a store and a box file, builds one cell's
 * potentially visible set and prints its size (or, with --json, the same JSON as
 * `vocc pvs --json`, which `make test` compares).
 *
 *   pvs STORE BOXES (--cell ID | --at X,Y) [--json]
 *
 * STORE is a file written by `vocc bake`. BOXES is the text file `vocc boxes` writes from the
 * same scene files and reader flags: one object per line, "ID xmin ymin zmin xmax ymax zmax" in
 * world coordinates, ID its input feature number, objects in the scene's order; lines starting
 * with '#' are comments, and "# scene FINGERPRINT objects N ..." names the scene, which is
 * checked against the store's (a box file of another scene is refused). The PVS is printed by
 * id, the numbering of `vocc pvs`. --at takes a world position. Exit status: 0, or 1 with a
 * message on stderr.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vocc.h"

/* Reads a whole file; NULL with a message on failure. */
static unsigned char *read_file(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "pvs: cannot open %s: %s\n", path, strerror(errno));
        return NULL;
    }
    size_t cap = 1 << 16, n = 0;
    unsigned char *buf = malloc(cap);
    while (buf) {
        n += fread(buf + n, 1, cap - n, f);
        if (n < cap) break;
        unsigned char *bigger = realloc(buf, cap *= 2);
        if (!bigger) free(buf);
        buf = bigger;
    }
    if (!buf || ferror(f)) {
        fprintf(stderr, "pvs: cannot read %s\n", path);
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *len = n;
    return buf;
}

/* A box file, as `vocc boxes` writes it: per object its id (input feature number) and box. */
typedef struct {
    double *boxes;      /* 6 doubles per object: xmin ymin zmin xmax ymax zmax, world */
    uint32_t *ids;      /* per object, its id */
    size_t count;
    int has_scene;      /* whether the "# scene" line was there */
    unsigned long long scene;
    unsigned long objects;
} BoxFile;

/* Reads the box file; 0 with a message on failure. */
static int read_boxes(const char *path, BoxFile *out) {
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "pvs: cannot open %s: %s\n", path, strerror(errno));
        return 0;
    }
    size_t cap = 1024, n = 0, line_no = 0;
    double *boxes = malloc(cap * 6 * sizeof *boxes);
    uint32_t *ids = malloc(cap * sizeof *ids);
    char line[512];
    int ok = boxes && ids;
    while (ok && fgets(line, sizeof line, f)) {
        line_no++;
        char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (*p == '#') {
            /* "# scene FINGERPRINT objects N crs "NAME"": what to check against the store. */
            if (sscanf(p, "# scene %llx objects %lu", &out->scene, &out->objects) == 2)
                out->has_scene = 1;
            continue;
        }
        if (*p == '\n' || *p == '\r' || *p == '\0') continue;
        if (n == cap) {
            cap *= 2;
            double *b = realloc(boxes, cap * 6 * sizeof *boxes);
            if (b) boxes = b;
            uint32_t *d = realloc(ids, cap * sizeof *ids);
            if (d) ids = d;
            if (!b || !d) {
                fprintf(stderr, "pvs: out of memory reading %s\n", path);
                ok = 0;
                break;
            }
        }
        char *end;
        unsigned long id = strtoul(p, &end, 10);
        ok = end != p && id <= 0xFFFFFFFFul;
        p = end;
        for (int k = 0; ok && k < 6; k++) {
            boxes[6 * n + k] = strtod(p, &end);
            ok = end != p;
            p = end;
        }
        if (!ok) {
            fprintf(stderr,
                    "pvs: %s:%zu: expected an id and 6 numbers, ID XMIN YMIN ZMIN XMAX YMAX ZMAX "
                    "(`vocc boxes` writes this file)\n",
                    path, line_no);
            break;
        }
        ids[n++] = (uint32_t)id;
    }
    fclose(f);
    if (!ok) {
        free(boxes);
        free(ids);
        return 0;
    }
    out->boxes = boxes;
    out->ids = ids;
    out->count = n;
    return 1;
}

int main(int argc, char **argv) {
    if (argc < 5) {
        fprintf(stderr, "usage: pvs STORE BOXES (--cell ID | --at X,Y) [--json]\n");
        return 1;
    }
    const char *store_path = argv[1], *boxes_path = argv[2];
    int json = argc > 5 && strcmp(argv[5], "--json") == 0;
    int rc = 1;
    VoccError err;
    VoccStore *store = NULL;
    VoccTree *tree = NULL;
    VoccQuery *query = NULL;
    uint32_t *ids = NULL;
    size_t store_len = 0, objects = 0;
    BoxFile bf = {0};
    unsigned char *bytes = read_file(store_path, &store_len);
    if (!bytes || !read_boxes(boxes_path, &bf)) goto done;
    double *boxes = bf.boxes;
    objects = bf.count;

    /* Once per store: open it (the bytes stay ours and must outlive the store). */
    if (vocc_store_open(bytes, store_len, &store, &err) != VOCC_OK) {
        fprintf(stderr, "pvs: %s: %s\n", store_path, err.message);
        goto done;
    }
    VoccFrame frame;
    vocc_store_frame(store, &frame);

    /* The boxes must be those of the scene the store was baked from (a 1.0 store records none). */
    VoccStoreInfo info;
    vocc_store_info(store, &info);
    if (info.scene == 0) {
        fprintf(stderr, "pvs: note: %s (store %u.%u) records no scene: the boxes could not be "
                "checked against it\n", store_path, info.major, info.minor);
    } else if (!bf.has_scene) {
        fprintf(stderr, "pvs: note: %s names no scene: the boxes could not be checked against "
                "the store\n", boxes_path);
    } else if (bf.scene != info.scene || (info.objects != 0 && bf.objects != info.objects)) {
        fprintf(stderr, "pvs: %s holds another scene than the one %s was baked from (%lu objects, "
                "fingerprint %016llx; baked: %u objects, fingerprint %016llx): write it with "
                "`vocc boxes` from the files and reader flags of the bake\n", boxes_path,
                store_path, bf.objects, bf.scene, info.objects, (unsigned long long)info.scene);
        goto done;
    }

    /* Once per scene: the box tree (world boxes, so with the frame's origin) and a query. */
    if (vocc_tree_new(boxes, objects, frame.origin, &tree, &err) != VOCC_OK ||
        vocc_query_new(tree, &query, &err) != VOCC_OK) {
        fprintf(stderr, "pvs: %s\n", err.message);
        goto done;
    }
    ids = malloc((objects ? objects : 1) * sizeof *ids);
    if (!ids) goto done;

    /* On cell entry: which cell, its record, its PVS. No allocation from here on. */
    uint32_t id;
    if (strcmp(argv[3], "--cell") == 0) {
        char *end;
        unsigned long v = strtoul(argv[4], &end, 10);
        if (*end != '\0' || v >= vocc_store_cell_count(store)) {
            fprintf(stderr, "pvs: cell %s is outside the grid (cells 0..%u)\n", argv[4],
                    vocc_store_cell_count(store));
            goto done;
        }
        id = (uint32_t)v;
    } else if (strcmp(argv[3], "--at") == 0) {
        double x, y;
        if (sscanf(argv[4], "%lf,%lf", &x, &y) != 2) {
            fprintf(stderr, "pvs: --at takes X,Y\n");
            goto done;
        }
        if (vocc_cell_at_world(&frame, x, y, &id) != VOCC_OK) {
            fprintf(stderr, "pvs: (%g, %g) lies outside the store's grid\n", x, y);
            goto done;
        }
    } else {
        fprintf(stderr, "pvs: give --cell ID or --at X,Y\n");
        goto done;
    }
    VoccCell cell;
    size_t count = 0;
    if (vocc_store_cell(store, id, &cell, &err) != VOCC_OK ||
        vocc_pvs(query, tree, &frame, id, &cell, ids, objects, &count, &err) != VOCC_OK) {
        fprintf(stderr, "pvs: cell %u: %s\n", id, err.message);
        goto done;
    }

    if (json) {
        printf("{\"cell\":%u,\"objects\":%zu,\"pvs\":[", id, objects);
        /* PVS entries are positions in the box array; the file's ids are what they name. */
        for (size_t i = 0; i < count; i++) printf(i ? ",%u" : "%u", bf.ids[ids[i]]);
        printf("]}\n");
    } else {
        /* What the store says about itself (a 1.0 store records no scene), and the cell's VOs
           as stored: endpoint grid indices with their exponents, and the height level. */
        printf("store %u.%u, baked for %u objects, scene %016llx, CRS \"%s\"\n", info.major,
               info.minor, info.objects, (unsigned long long)info.scene, info.crs);
        printf("cell %u: %zu of %zu objects potentially visible, %u VOs%s\n", id, count,
               objects, cell.count, cell.skipped ? " (skipped: inside a building)" : "");
        for (unsigned k = 0; k < cell.count; k++) {
            const VoccVo *v = &cell.vos[k];
            printf("  VO %u: (e %u, x %u, y %u) - (e %u, x %u, y %u), level %u\n", k,
                   (unsigned)v->exp1, (unsigned)v->x1, (unsigned)v->y1, (unsigned)v->exp2,
                   (unsigned)v->x2, (unsigned)v->y2, (unsigned)v->level);
        }
    }
    rc = 0;
done:
    free(ids);
    vocc_query_free(query);
    vocc_tree_free(tree);
    vocc_store_free(store);
    free(bf.boxes);
    free(bf.ids);
    free(bytes);
    return rc;
}
