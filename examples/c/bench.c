/*
 * bench.c: µs per cell entry through the C ABI, the C side of benches/culler.rs.
 *
 *   bench STORE BOXES [PASSES]
 *
 * Setup (not timed): open the store, build the box tree from BOXES (a box file as `vocc boxes`
 * writes it, world coordinates, as for pvs.c), make a query. A cell entry is what an engine does when the camera enters a cell:
 * vocc_store_cell, then vocc_pvs into a caller buffer of vocc_tree_len ids (and, timed
 * apart, with ids NULL, reading the result in place through vocc_query_ids). Cells are the
 * store's cells with VOs, entered round robin as in the Rust benchmark. Each of PASSES
 * samples (default 30) enters every such cell once; a sample's time divided by its cell count
 * is one µs-per-entry figure, and the median over the samples is printed.
 */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "vocc.h"

static double now_us(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e6 + t.tv_nsec / 1e3;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static unsigned char *slurp(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = n > 0 ? malloc((size_t)n) : NULL;
    if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
        free(b);
        b = NULL;
    }
    fclose(f);
    *len = (size_t)n;
    return b;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: bench STORE BOXES [PASSES]\n");
        return 1;
    }
    int passes = argc > 3 ? atoi(argv[3]) : 30;
    if (passes < 1) passes = 1;
    size_t len, text_len;
    unsigned char *bytes = slurp(argv[1], &len);
    char *text = (char *)slurp(argv[2], &text_len);
    if (!bytes || !text) {
        fprintf(stderr, "bench: cannot read %s or %s\n", argv[1], argv[2]);
        return 1;
    }
    text = realloc(text, text_len + 1);
    text[text_len] = '\0';
    size_t objects = 0, cap = 1024;
    double *boxes = malloc(cap * 6 * sizeof *boxes);
    /* The box file of `vocc boxes`: '#' lines, then "ID xmin ymin zmin xmax ymax zmax" lines
       (the ids are not needed to time the culler). */
    for (char *p = text; *p;) {
        char *eol = strchr(p, '\n');
        if (eol) *eol = '\0';
        char *end;
        strtoul(p, &end, 10);
        if (*p != '#' && end != p) {
            if (objects == cap) boxes = realloc(boxes, (cap *= 2) * 6 * sizeof *boxes);
            for (int k = 0; k < 6; k++) boxes[objects * 6 + k] = strtod(end, &end);
            objects++;
        }
        if (!eol) break;
        p = eol + 1;
    }
    VoccError err;
    VoccStore *store;
    VoccTree *tree;
    VoccQuery *query;
    VoccFrame frame;
    if (vocc_store_open(bytes, len, &store, &err) != VOCC_OK) {
        fprintf(stderr, "bench: %s\n", err.message);
        return 1;
    }
    vocc_store_frame(store, &frame);
    if (vocc_tree_new(boxes, objects, frame.origin, &tree, &err) != VOCC_OK ||
        vocc_query_new(tree, &query, &err) != VOCC_OK) {
        fprintf(stderr, "bench: %s\n", err.message);
        return 1;
    }
    uint32_t n_cells = vocc_store_cell_count(store), *cells = malloc(n_cells * sizeof *cells);
    uint32_t with_vos = 0;
    for (uint32_t id = 0; id < n_cells; id++) {
        VoccCell c;
        if (vocc_store_cell(store, id, &c, NULL) == VOCC_OK && !c.skipped && c.count > 0)
            cells[with_vos++] = id;
    }
    if (with_vos == 0) {
        fprintf(stderr, "bench: no cell has a VO\n");
        return 1;
    }
    uint32_t *ids = malloc(objects * sizeof *ids);
    double *copy = malloc(passes * sizeof *copy), *in_place = malloc(passes * sizeof *in_place);
    size_t visible = 0, sink = 0;
    for (int round = -1; round < passes; round++) { /* round -1 warms up */
        for (int mode = 0; mode < 2; mode++) {
            double t0 = now_us();
            for (uint32_t k = 0; k < with_vos; k++) {
                VoccCell c;
                size_t count;
                uint32_t id = cells[k];
                vocc_store_cell(store, id, &c, NULL);
                if (mode == 0) {
                    vocc_pvs(query, tree, &frame, id, &c, ids, objects, &count, NULL);
                    sink += ids[count ? count - 1 : 0];
                } else {
                    vocc_pvs(query, tree, &frame, id, &c, NULL, 0, &count, NULL);
                    const uint32_t *v = vocc_query_ids(query, &count);
                    sink += count ? v[count - 1] : 0;
                }
                visible += count;
            }
            double per = (now_us() - t0) / with_vos;
            if (round >= 0) (mode == 0 ? copy : in_place)[round] = per;
        }
    }
    qsort(copy, passes, sizeof *copy, cmp);
    qsort(in_place, passes, sizeof *in_place, cmp);
    printf("%zu objects, %u cells with VOs, %.1f objects visible per cell entry\n", objects,
           with_vos, (double)visible / ((passes + 1) * 2.0 * with_vos));
    printf("C ABI, ids copied to the caller: median %.2f us per cell entry (min %.2f, max %.2f, %d samples)\n",
           copy[passes / 2], copy[0], copy[passes - 1], passes);
    printf("C ABI, ids read in place:        median %.2f us per cell entry (min %.2f, max %.2f)\n",
           in_place[passes / 2], in_place[0], in_place[passes - 1]);
    if (sink == 42) printf("\n");
    vocc_query_free(query);
    vocc_tree_free(tree);
    vocc_store_free(store);
    free(bytes);
    free(text);
    free(boxes);
    free(ids);
    free(cells);
    free(copy);
    free(in_place);
    return 0;
}
