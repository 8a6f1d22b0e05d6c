/*
 * pvs.c: vocc's C ABI as an engine uses it. Reads a store and a box file, builds one cell's
 * potentially visible set and prints its size (or, with --json, the same JSON as
 * `vocc pvs --json`, which `make test` compares).
 *
 *   pvs STORE BOXES (--cell ID | --at X,Y) [--json]
 *
 * STORE is a file written by `vocc bake`. BOXES is a text file with one object box per line,
 * "xmin ymin zmin xmax ymax zmax" in world coordinates, objects in the scene's order (lines
 * starting with '#' are comments); `cargo run --example boxes` writes one from scene files.
 * --at takes a world position. Exit status: 0, or 1 with a message on stderr.
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

/* Reads the box file: 6 doubles per object; NULL with a message on failure. */
static double *read_boxes(const char *path, size_t *count) {
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "pvs: cannot open %s: %s\n", path, strerror(errno));
        return NULL;
    }
    size_t cap = 1024, n = 0, line_no = 0;
    double *boxes = malloc(cap * 6 * sizeof *boxes);
    char line[512];
    while (boxes && fgets(line, sizeof line, f)) {
        line_no++;
        char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (*p == '#' || *p == '\n' || *p == '\r' || *p == '\0') continue;
        if (n == cap) {
            double *bigger = realloc(boxes, (cap *= 2) * 6 * sizeof *boxes);
            if (!bigger) free(boxes);
            boxes = bigger;
            if (!boxes) break;
        }
        for (int k = 0; k < 6; k++) {
            char *end;
            boxes[6 * n + k] = strtod(p, &end);
            if (end == p) {
                fprintf(stderr, "pvs: %s:%zu: expected 6 numbers\n", path, line_no);
                free(boxes);
                fclose(f);
                return NULL;
            }
            p = end;
        }
        n++;
    }
    if (!boxes) fprintf(stderr, "pvs: out of memory reading %s\n", path);
    fclose(f);
    *count = n;
    return boxes;
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
    unsigned char *bytes = read_file(store_path, &store_len);
    double *boxes = bytes ? read_boxes(boxes_path, &objects) : NULL;
    if (!boxes) goto done;

    /* Once per store: open it (the bytes stay ours and must outlive the store). */
    if (vocc_store_open(bytes, store_len, &store, &err) != VOCC_OK) {
        fprintf(stderr, "pvs: %s: %s\n", store_path, err.message);
        goto done;
    }
    VoccFrame frame;
    vocc_store_frame(store, &frame);

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
        for (size_t i = 0; i < count; i++) printf(i ? ",%u" : "%u", ids[i]);
        printf("]}\n");
    } else {
        /* What the store says about itself (a 1.0 store records no scene), and the cell's VOs
           as stored: endpoint grid indices with their exponents, and the height level. */
        VoccStoreInfo info;
        vocc_store_info(store, &info);
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
    free(boxes);
    free(bytes);
    return rc;
}
