/*
 * blind_test.c: the four queries of the C interface on two tree files, printed as one JSON
 * object, for comparison with `ist query ... --json` (see blind.sh).
 *
 * Usage: blind_test A.ist B.ist tx ty tz qw qx qy qz [stiffness] [reuse]
 *
 * Body A sits at the identity, body B at the given pose (q = {w, x, y, z}). Each query runs
 * on a pair whose temporal coherence was just forgotten (ist_pair_reset), as a fresh
 * `ist query` process sees it; with the word "reuse" as the last argument the four queries
 * share one pair without resets (the order: distance, contact, penetration, multipoint).
 * Without a stiffness, the penetration uses ist_penetration (stiffness 1, the default of
 * `ist query --stiffness`); with one, ist_penetration_with_stiffness. Multipoint uses k = 16,
 * the default of `ist query --k` (the split depth 4 of `ist query --split-depth` is fixed
 * by ist_multipoint).
 *
 * Written against include/innersphere.h alone. C99.
 */

#include "innersphere.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MULTIPOINT_K 16

static const char *argv0 = "blind_test";

static void die(const char *what, int status) {
    fprintf(stderr, "%s: %s failed (status %d): %s\n", argv0, what, status, ist_last_error());
    exit(1);
}

static double parse_double(const char *s, const char *name) {
    char *end = NULL;
    double v = strtod(s, &end);
    if (end == s || *end != '\0') {
        fprintf(stderr, "%s: %s: not a number: '%s'\n", argv0, name, s);
        exit(2);
    }
    return v;
}

/* A double as a JSON number that reads back to the same double ("%.17g"); non-finite
 * values as the NaN / Infinity tokens that Python's json module accepts. */
static void put_double(double v) {
    if (isnan(v)) {
        fputs("NaN", stdout);
    } else if (isinf(v)) {
        fputs(v > 0 ? "Infinity" : "-Infinity", stdout);
    } else {
        printf("%.17g", v);
    }
}

static void put_vec3(const char *key, const double v[3]) {
    printf("\"%s\": [", key);
    put_double(v[0]);
    fputs(", ", stdout);
    put_double(v[1]);
    fputs(", ", stdout);
    put_double(v[2]);
    fputs("]", stdout);
}

static void put_key_double(const char *key, double v) {
    printf("\"%s\": ", key);
    put_double(v);
}

int main(int argc, char **argv) {
    ist_pose pose_a;
    ist_pose pose_b;
    ist_tree *a;
    ist_tree *b;
    ist_pair *pair;
    ist_distance_result dist;
    ist_penetration_result pen;
    ist_contact_point contacts[MULTIPOINT_K];
    size_t contact_count = 0;
    int in_contact = -1;
    int have_stiffness = 0;
    int reuse = 0;
    double stiffness = 1.0;
    int st;
    int i;
    size_t j;

    if (argc > 0 && argv[0] != NULL) {
        argv0 = argv[0];
    }
    if (argc >= 11 && strcmp(argv[argc - 1], "reuse") == 0) {
        reuse = 1;
        argc--;
    }
    if (argc != 10 && argc != 11) {
        fprintf(stderr, "usage: %s A.ist B.ist tx ty tz qw qx qy qz [stiffness] [reuse]\n", argv0);
        return 2;
    }

    pose_a = ist_pose_identity();
    for (i = 0; i < 3; i++) {
        pose_b.t[i] = parse_double(argv[3 + i], "translation");
    }
    for (i = 0; i < 4; i++) {
        pose_b.q[i] = parse_double(argv[6 + i], "quaternion");
    }
    if (argc == 11) {
        have_stiffness = 1;
        stiffness = parse_double(argv[10], "stiffness");
    }

    a = ist_tree_load(argv[1]);
    if (a == NULL) {
        die("ist_tree_load(A)", -1);
    }
    b = ist_tree_load(argv[2]);
    if (b == NULL) {
        die("ist_tree_load(B)", -1);
    }
    pair = ist_pair_new(a, b);
    if (pair == NULL) {
        die("ist_pair_new", -1);
    }
    /* The pair keeps its trees alive (header, "Ownership"). */
    ist_tree_free(a);
    ist_tree_free(b);

    /* distance */
    if (!reuse && (st = ist_pair_reset(pair)) != IST_OK) {
        die("ist_pair_reset", st);
    }
    memset(&dist, 0, sizeof dist);
    if ((st = ist_distance(pair, &pose_a, &pose_b, &dist)) != IST_OK) {
        die("ist_distance", st);
    }

    /* contact */
    if (!reuse && (st = ist_pair_reset(pair)) != IST_OK) {
        die("ist_pair_reset", st);
    }
    if ((st = ist_contact(pair, &pose_a, &pose_b, &in_contact)) != IST_OK) {
        die("ist_contact", st);
    }

    /* penetration (patches are read below, right after it, before any other query) */
    if (!reuse && (st = ist_pair_reset(pair)) != IST_OK) {
        die("ist_pair_reset", st);
    }
    memset(&pen, 0, sizeof pen);
    if (have_stiffness) {
        st = ist_penetration_with_stiffness(pair, &pose_a, &pose_b, stiffness, &pen);
    } else {
        st = ist_penetration(pair, &pose_a, &pose_b, &pen);
    }
    if (st != IST_OK) {
        die(have_stiffness ? "ist_penetration_with_stiffness" : "ist_penetration", st);
    }

    printf("{\n  \"pose_b\": [");
    for (i = 0; i < 3; i++) {
        put_double(pose_b.t[i]);
        fputs(", ", stdout);
    }
    for (i = 0; i < 4; i++) {
        put_double(pose_b.q[i]);
        fputs(i < 3 ? ", " : "", stdout);
    }
    printf("],\n  \"reuse\": %s,\n", reuse ? "true" : "false");

    printf("  \"distance\": {");
    put_key_double("distance", dist.distance);
    printf(", \"contact\": %d, ", dist.contact);
    put_vec3("point_a", dist.point_a);
    fputs(", ", stdout);
    put_vec3("point_b", dist.point_b);
    printf("},\n");

    printf("  \"contact\": {\"contact\": %d},\n", in_contact);

    printf("  \"penetration\": {");
    put_key_double("stiffness", stiffness);
    fputs(", ", stdout);
    put_key_double("volume", pen.volume);
    fputs(", ", stdout);
    put_key_double("max_depth", pen.max_depth);
    fputs(", ", stdout);
    put_vec3("normal", pen.normal);
    fputs(", ", stdout);
    put_vec3("force", pen.force);
    fputs(", ", stdout);
    put_vec3("torque_a", pen.torque_a);
    fputs(", ", stdout);
    put_vec3("torque_b", pen.torque_b);
    printf(", \"patch_count\": %zu, \"patches\": [", pen.patch_count);
    for (j = 0; j < pen.patch_count; j++) {
        ist_patch patch;
        memset(&patch, 0, sizeof patch);
        if ((st = ist_penetration_patch(pair, j, &patch)) != IST_OK) {
            die("ist_penetration_patch", st);
        }
        printf("%s\n    {", j == 0 ? "" : ",");
        put_vec3("point", patch.point);
        fputs(", ", stdout);
        put_vec3("normal", patch.normal);
        fputs(", ", stdout);
        put_key_double("depth", patch.depth);
        fputs(", ", stdout);
        put_key_double("volume", patch.volume);
        printf(", \"pairs\": %lu}", (unsigned long)patch.pairs);
    }
    printf("]},\n");

    /* multipoint */
    if (!reuse && (st = ist_pair_reset(pair)) != IST_OK) {
        die("ist_pair_reset", st);
    }
    memset(contacts, 0, sizeof contacts);
    if ((st = ist_multipoint(pair, &pose_a, &pose_b, MULTIPOINT_K, contacts, &contact_count)) !=
        IST_OK) {
        die("ist_multipoint", st);
    }
    if (contact_count > MULTIPOINT_K) {
        fprintf(stderr, "%s: ist_multipoint reported %zu contacts for k = %d\n", argv0,
                contact_count, MULTIPOINT_K);
        return 1;
    }
    printf("  \"multipoint\": {\"k\": %d, \"count\": %zu, \"contacts\": [", MULTIPOINT_K,
           contact_count);
    for (j = 0; j < contact_count; j++) {
        printf("%s\n    {", j == 0 ? "" : ",");
        put_vec3("point", contacts[j].point);
        fputs(", ", stdout);
        put_vec3("normal", contacts[j].normal);
        fputs(", ", stdout);
        put_key_double("depth", contacts[j].depth);
        printf(", \"leaf_a\": %lu, \"leaf_b\": %lu}", (unsigned long)contacts[j].leaf_a,
               (unsigned long)contacts[j].leaf_b);
    }
    printf("]}\n}\n");

    ist_pair_free(pair);
    return 0;
}
