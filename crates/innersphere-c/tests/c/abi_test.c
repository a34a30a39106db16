/* The C ABI against the Rust answers: prints every query's answer at every pose of
 * DIR/poses.txt and the haptic loop's along DIR/device.txt in the format of
 * `cargo run --example reference answer DIR` (run.sh diffs the two: bit for bit), then
 * checks the error paths (bad paths, a corrupt file, NULL pointers, NaN poses, bad
 * arguments), and runs the haptic loop with its collision thread in real time (passive,
 * models published, freed cleanly). Written against include/innersphere.h only. */
#define _POSIX_C_SOURCE 200809L
#include "innersphere.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int failures = 0;

#define CHECK(cond, ...)                                                          \
    do {                                                                          \
        if (!(cond)) {                                                            \
            fprintf(stderr, "FAILED (%s:%d): %s: ", __FILE__, __LINE__, #cond);   \
            fprintf(stderr, __VA_ARGS__);                                         \
            fprintf(stderr, " [last error: %s]\n", ist_last_error());             \
            failures++;                                                           \
        }                                                                         \
    } while (0)

static void bits(double x) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    printf(" %016llx", (unsigned long long)u);
}

static void v3(const double x[3]) {
    bits(x[0]);
    bits(x[1]);
    bits(x[2]);
}

static int read_pose(FILE* f, ist_pose* p) {
    double x[7];
    for (int i = 0; i < 7; i++)
        if (fscanf(f, "%lf", &x[i]) != 1) return 0;
    for (int i = 0; i < 3; i++) p->t[i] = x[i];
    for (int i = 0; i < 4; i++) p->q[i] = x[3 + i];
    return 1;
}

static char* join(const char* dir, const char* file) {
    size_t n = strlen(dir) + strlen(file) + 2;
    char* s = malloc(n);
    snprintf(s, n, "%s/%s", dir, file);
    return s;
}

/* Trees `a` and `b` given their meshes (`dir`'s a.stl and b.stl), into `am` and `bm`. */
static void with_meshes(const char* dir, const ist_tree* a, const ist_tree* b, ist_tree** am,
                        ist_tree** bm) {
    char* mesh_a = join(dir, "a.stl");
    char* mesh_b = join(dir, "b.stl");
    *am = ist_tree_with_mesh(a, mesh_a);
    *bm = ist_tree_with_mesh(b, mesh_b);
    free(mesh_a);
    free(mesh_b);
    CHECK(*am != NULL && *bm != NULL, "ist_tree_with_mesh");
}

static void answers(const char* dir, ist_tree* a, ist_tree* b) {
    ist_pair* pair = ist_pair_new(a, b);
    CHECK(pair != NULL, "ist_pair_new");
    ist_tree *am, *bm;
    with_meshes(dir, a, b, &am, &bm);
    ist_pair* refined = ist_pair_new(am, bm);
    CHECK(refined != NULL, "ist_pair_new with meshes");
    ist_tree_free(am);
    ist_tree_free(bm);
    char* path = join(dir, "poses.txt");
    FILE* f = fopen(path, "r");
    free(path);
    ist_pose pa, pb;
    for (int i = 0; f && read_pose(f, &pa) && read_pose(f, &pb); i++) {
        ist_distance_result d;
        CHECK(ist_distance(pair, &pa, &pb, &d) == IST_OK, "distance");
        printf("%d distance", i);
        bits(d.distance);
        printf(" %d", d.contact);
        v3(d.point_a);
        v3(d.point_b);
        printf("\n");
        ist_refined_distance_result r;
        CHECK(ist_refined_distance(refined, &pa, &pb, NULL, &r) == IST_OK, "refined distance");
        printf("%d refined", i);
        bits(r.distance);
        printf(" %d %d %d", r.contact, r.refined, r.complete);
        v3(r.point_a);
        v3(r.point_b);
        printf(" %u %u", r.tri_a, r.tri_b);
        bits(r.sphere_distance);
        printf("\n");
        int in_contact = -1;
        CHECK(ist_contact(pair, &pa, &pb, &in_contact) == IST_OK, "contact");
        printf("%d contact %d\n", i, in_contact);
        int dt = -1, bt = -1;
        CHECK(ist_distance_traversal(pair, &pa, &pb, &dt) == IST_OK, "distance traversal");
        CHECK(ist_backtracking(pair, &pa, &pb, &bt) == IST_OK, "backtracking");
        printf("%d traversals %d %d\n", i, dt, bt);
        ist_budgeted_result w;
        CHECK(ist_penetration_within(pair, &pa, &pb, 500, 2.5, &w) == IST_OK, "within");
        printf("%d within", i);
        bits(w.volume);
        bits(w.upper_bound);
        printf(" %d", w.complete);
        bits(w.max_depth);
        v3(w.normal);
        v3(w.force);
        v3(w.torque_b);
        printf(" %llu\n", (unsigned long long)w.visits);
        ist_penetration_result p;
        CHECK(ist_penetration_with_stiffness(pair, &pa, &pb, 2.5, &p) == IST_OK, "penetration");
        printf("%d penetration", i);
        bits(p.volume);
        bits(p.max_depth);
        v3(p.normal);
        v3(p.force);
        v3(p.torque_a);
        v3(p.torque_b);
        printf(" %zu\n", p.patch_count);
        for (size_t j = 0; j < p.patch_count; j++) {
            ist_patch x;
            CHECK(ist_penetration_patch(pair, j, &x) == IST_OK, "patch %zu", j);
            printf("%d patch %zu", i, j);
            v3(x.point);
            v3(x.normal);
            bits(x.depth);
            bits(x.volume);
            printf(" %u\n", x.pairs);
        }
        ist_contact_point cs[8];
        size_t n = 99;
        CHECK(ist_multipoint(pair, &pa, &pb, 8, cs, &n) == IST_OK, "multipoint");
        printf("%d multipoint %zu\n", i, n);
        for (size_t j = 0; j < n; j++) {
            printf("%d contact_point %zu", i, j);
            v3(cs[j].point);
            v3(cs[j].normal);
            bits(cs[j].depth);
            printf(" %u %u\n", cs[j].leaf_a, cs[j].leaf_b);
        }
    }
    if (f) fclose(f);

    ist_haptic_params hp;
    CHECK(ist_haptic_params_default(IST_DEVICE_OMEGA, &hp) == IST_OK, "params");
    hp.budget = 1.0;
    hp.contact_stiffness = 2.0;
    path = join(dir, "device.txt");
    f = fopen(path, "r");
    free(path);
    ist_pose dev;
    CHECK(f && read_pose(f, &dev), "device file");
    hp.start = dev;
    ist_haptic* h = ist_haptic_new(pair, &hp);
    CHECK(h != NULL, "ist_haptic_new");
    for (int i = 0; h; i++) {
        ist_haptic_output o;
        CHECK(ist_haptic_tick(h, &dev, 0.001, &o) == IST_OK, "tick %d", i);
        printf("%d tick", i);
        v3(o.force);
        v3(o.torque);
        v3(o.tool.t);
        for (int k = 0; k < 4; k++) bits(o.tool.q[k]);
        bits(o.volume);
        bits(o.max_depth);
        printf("\n");
        if (!read_pose(f, &dev)) break;
    }
    if (f) fclose(f);
    double now = 1.0, max = 1.0;
    CHECK(ist_haptic_energy(h, &now, &max) == IST_OK, "energy");
    printf("energy");
    bits(now);
    printf("\n");
    CHECK(max <= 1e-12, "energy to the hand rose to %g J", max);
    ist_haptic_free(h);
    ist_pair_free(pair);
    ist_pair_free(refined);
}

/* The haptic loop with its collision thread, paced at 1 kHz along DIR/device.txt: every
 * tick answers, the models arrive, the loop stays passive; bad collision options are
 * refused. Prints nothing (its answers depend on timing). */
static void multirate(const char* dir, ist_tree* a, ist_tree* b) {
    ist_pair* pair = ist_pair_new(a, b);
    ist_haptic_params hp;
    CHECK(ist_haptic_params_default(IST_DEVICE_OMEGA, &hp) == IST_OK, "params");
    hp.contact_stiffness = 2.0;
    hp.collision_thread = 1;
    char* path = join(dir, "device.txt");
    FILE* f = fopen(path, "r");
    free(path);
    ist_pose dev;
    CHECK(f && read_pose(f, &dev), "device file");
    hp.start = dev;
    ist_haptic* h = ist_haptic_new(pair, &hp);
    CHECK(h != NULL, "ist_haptic_new with a collision thread");
    struct timespec due;
    clock_gettime(CLOCK_MONOTONIC, &due);
    int ticks = 0, touching = 0;
    while (h) {
        due.tv_nsec += 1000000;
        if (due.tv_nsec >= 1000000000) {
            due.tv_nsec -= 1000000000;
            due.tv_sec += 1;
        }
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &due, NULL);
        ist_haptic_output o;
        CHECK(ist_haptic_tick(h, &dev, 0.001, &o) == IST_OK, "multi-rate tick %d", ticks);
        CHECK(isfinite(o.model_age_seconds) && o.model_age_seconds >= 0.0, "model age %g",
              o.model_age_seconds);
        touching += o.volume > 0.0;
        ticks++;
        if (!read_pose(f, &dev)) break;
    }
    if (f) fclose(f);
    uint64_t queries = 0;
    CHECK(ist_haptic_collision_queries(h, &queries) == IST_OK && queries > 100,
          "%llu collision queries in %d ticks", (unsigned long long)queries, ticks);
    CHECK(touching > 0, "the tool never touched");
    double max = 1.0;
    CHECK(ist_haptic_energy(h, NULL, &max) == IST_OK && max <= 1e-9,
          "energy to the hand rose to %g J", max);
    ist_haptic_free(h);
    hp.collision_thread = 2;
    CHECK(ist_haptic_new(pair, &hp) == NULL, "collision_thread 2");
    hp.collision_thread = 1;
    hp.collision_delay = -1.0;
    CHECK(ist_haptic_new(pair, &hp) == NULL, "negative collision delay");
    ist_pair_free(pair);
}

static void errors(const char* dir, ist_tree* a, ist_tree* b) {
    /* Bad paths and a corrupt file: NULL and a message. */
    CHECK(ist_tree_load("/nonexistent/x.ist") == NULL, "missing file");
    CHECK(strlen(ist_last_error()) > 0, "no message");
    CHECK(ist_last_status() == IST_ERR_IO, "a missing file is IST_ERR_IO");
    CHECK(ist_tree_load(NULL) == NULL, "NULL path");
    CHECK(strstr(ist_last_error(), "NULL") != NULL, "message names NULL");
    CHECK(ist_last_status() == IST_ERR_NULL, "a NULL path is IST_ERR_NULL");
    char* corrupt = join(dir, "corrupt.ist");
    FILE* f = fopen(corrupt, "wb");
    fputs("ISTREE garbage, not a tree", f);
    fclose(f);
    CHECK(ist_tree_load(corrupt) == NULL, "corrupt file");
    CHECK(ist_last_status() == IST_ERR_CORRUPT_TREE, "a corrupt file is IST_ERR_CORRUPT_TREE");
    free(corrupt);
    char* notmesh = join(dir, "poses.txt");
    CHECK(ist_tree_build(notmesh, NULL) == NULL, "not a mesh");
    CHECK(ist_last_status() == IST_ERR_MESH, "a file that is no mesh is IST_ERR_MESH");
    free(notmesh);
    ist_build_options bo = ist_build_options_default();
    bo.voxel_size = -1.0;
    CHECK(ist_tree_build("/nonexistent.stl", &bo) == NULL, "bad options");

    /* NULL pointers. */
    ist_pair* pair = ist_pair_new(a, b);
    ist_pose id = ist_pose_identity();
    ist_distance_result d;
    int c;
    ist_penetration_result p;
    ist_patch patch;
    ist_contact_point cs[4];
    size_t n;
    CHECK(ist_pair_new(NULL, b) == NULL, "pair of NULL");
    CHECK(ist_distance(NULL, &id, &id, &d) == IST_ERR_NULL, "NULL pair");
    CHECK(ist_distance(pair, NULL, &id, &d) == IST_ERR_NULL, "NULL pose");
    CHECK(ist_distance(pair, &id, &id, NULL) == IST_ERR_NULL, "NULL out");
    CHECK(ist_contact(pair, &id, &id, NULL) == IST_ERR_NULL, "NULL in_contact");
    CHECK(ist_penetration(pair, &id, NULL, &p) == IST_ERR_NULL, "NULL pose");
    CHECK(ist_multipoint(pair, &id, &id, 4, NULL, &n) == IST_ERR_NULL, "NULL out");
    CHECK(ist_multipoint(pair, &id, &id, 4, cs, NULL) == IST_ERR_NULL, "NULL count");
    CHECK(ist_tree_save(NULL, "x.ist") == IST_ERR_NULL, "NULL tree");
    CHECK(ist_pose_from_matrix(NULL, 1, &id) == IST_ERR_NULL, "NULL matrix");

    /* NaN and bad poses, bad arguments. */
    ist_pose nan_pose = id;
    nan_pose.t[1] = NAN;
    CHECK(ist_distance(pair, &id, &nan_pose, &d) == IST_ERR_POSE, "NaN pose");
    ist_pose zero_q = id;
    zero_q.q[0] = 0.0;
    CHECK(ist_contact(pair, &zero_q, &id, &c) == IST_ERR_POSE, "zero quaternion");
    CHECK(ist_multipoint(pair, &id, &id, 0, cs, &n) == IST_ERR_INVALID_ARGUMENT, "k = 0");
    CHECK(ist_penetration_with_stiffness(pair, &id, &id, -1.0, &p) == IST_ERR_INVALID_ARGUMENT,
          "negative stiffness");
    CHECK(ist_penetration(pair, &id, &id, &p) == IST_OK, "penetration");
    CHECK(ist_penetration_patch(pair, p.patch_count, &patch) == IST_ERR_INVALID_ARGUMENT,
          "patch past the end");
    double shear[16] = {1, 0.5, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    CHECK(ist_pose_from_matrix(shear, 1, &id) == IST_ERR_POSE, "not a rotation");
    double m[16] = {0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1}; /* column-major */
    ist_pose from_m;
    CHECK(ist_pose_from_matrix(m, 1, &from_m) == IST_OK, "matrix");
    CHECK(from_m.t[0] == 1 && from_m.t[1] == 2 && from_m.t[2] == 3, "translation column");
    CHECK(fabs(from_m.q[0] - sqrt(0.5)) < 1e-12 && fabs(from_m.q[3] - sqrt(0.5)) < 1e-12,
          "quarter turn about z");
    ist_haptic_params hp;
    CHECK(ist_haptic_params_default(42, &hp) == IST_ERR_INVALID_ARGUMENT, "unknown class");
    CHECK(ist_haptic_params_default(IST_DEVICE_TOUCH, &hp) == IST_OK, "touch");
    hp.rate = 0.0;
    CHECK(ist_haptic_new(pair, &hp) == NULL, "rate 0");
    CHECK(ist_haptic_params_default(IST_DEVICE_TOUCH, &hp) == IST_OK, "touch");
    ist_haptic* h = ist_haptic_new(pair, &hp);
    ist_haptic_output o;
    CHECK(h && ist_haptic_tick(h, &nan_pose, 0.001, &o) == IST_ERR_POSE, "NaN device");
    CHECK(h && ist_haptic_tick(h, &id, 0.001, NULL) == IST_ERR_NULL, "NULL out");
    /* A dt that is not 0 or a positive time is refused, not replaced. */
    const double bad_dt[] = {NAN, -1.0, INFINITY};
    for (int i = 0; i < 3; i++)
        CHECK(h && ist_haptic_tick(h, &id, bad_dt[i], &o) == IST_ERR_INVALID_ARGUMENT &&
                  strstr(ist_last_error(), "dt must be 0"),
              "dt %g", bad_dt[i]);
    ist_haptic_free(h);
    ist_haptic_free(NULL);
    /* A density whose mass overflows: a sentence with plain numbers, no debug dump. */
    CHECK(ist_haptic_params_default(IST_DEVICE_OMEGA, &hp) == IST_OK, "omega");
    hp.density = 1e300;
    CHECK(ist_haptic_new(pair, &hp) == NULL && !strstr(ist_last_error(), "DMat3") &&
              !strstr(ist_last_error(), "DVec3") && strlen(ist_last_error()) < 400,
          "density 1e300");
    /* A rate below 100 Hz is refused; at 100 Hz the defaults for the rate are passive. */
    CHECK(ist_haptic_params_for_rate(IST_DEVICE_OMEGA, 10.0, &hp) == IST_OK &&
              ist_haptic_new(pair, &hp) == NULL && strstr(ist_last_error(), "100 Hz"),
          "10 Hz");
    CHECK(ist_haptic_params_for_rate(IST_DEVICE_OMEGA, 100.0, &hp) == IST_OK, "100 Hz");
    h = ist_haptic_new(pair, &hp);
    CHECK(h != NULL, "the defaults at 100 Hz");
    ist_haptic_free(h);
    /* The 1 kHz defaults at 100 Hz: damping below k·T/2, refused with the reason. */
    CHECK(ist_haptic_params_default(IST_DEVICE_OMEGA, &hp) == IST_OK, "omega");
    hp.rate = 100.0;
    CHECK(ist_haptic_new(pair, &hp) == NULL && strstr(ist_last_error(), "k·T/2"),
          "1 kHz coupling at 100 Hz");
    /* A stiffness whose force overflows is refused. */
    ist_penetration_result pr;
    CHECK(ist_penetration_with_stiffness(pair, &id, &id, 1e308, &pr) == IST_ERR_INVALID_ARGUMENT,
          "stiffness 1e308");
    /* The refined distance: trees without meshes, a mesh that is not the tree's, bad
     * options. */
    ist_refined_distance_result rd;
    CHECK(ist_refined_distance(pair, &id, &id, NULL, &rd) == IST_ERR_INVALID_ARGUMENT &&
              strstr(ist_last_error(), "mesh"),
          "refined distance without meshes");
    char* mesh_b = join(dir, "b.stl");
    CHECK(ist_tree_with_mesh(a, mesh_b) == NULL && ist_last_status() == IST_ERR_MESH &&
              strstr(ist_last_error(), "not the mesh"),
          "B's mesh given to A");
    CHECK(ist_tree_with_mesh(a, NULL) == NULL && ist_last_status() == IST_ERR_NULL, "NULL mesh");
    free(mesh_b);
    ist_tree *am, *bm;
    with_meshes(dir, a, b, &am, &bm);
    ist_pair* rp = ist_pair_new(am, bm);
    ist_refine_options ro = ist_refine_options_default();
    CHECK(ro.radius_scale > 0 && ro.max_node_pairs > 0, "default refine options");
    ro.max_node_pairs = 0;
    CHECK(ist_refined_distance(rp, &id, &id, &ro, &rd) == IST_ERR_INVALID_ARGUMENT,
          "max_node_pairs 0");
    ro = ist_refine_options_default();
    ro.radius_scale = NAN;
    CHECK(ist_refined_distance(rp, &id, &id, &ro, &rd) == IST_ERR_INVALID_ARGUMENT,
          "NaN radius scale");
    CHECK(ist_refined_distance(rp, &id, &id, NULL, NULL) == IST_ERR_NULL, "NULL out");
    CHECK(ist_refined_distance(rp, &id, &nan_pose, NULL, &rd) == IST_ERR_POSE, "NaN pose");
    ist_pair_free(rp);
    ist_tree_free(am);
    ist_tree_free(bm);
    ist_pair_free(pair);
    ist_pair_free(NULL);
    ist_tree_free(NULL);
    CHECK(strlen(ist_version()) > 0, "version");
}

/* Whether two refined distances are the same bit for bit, field by field (the struct has
 * padding). */
static int same_refined(const ist_refined_distance_result* x, const ist_refined_distance_result* y) {
    return memcmp(&x->distance, &y->distance, sizeof(double)) == 0 && x->contact == y->contact &&
           x->refined == y->refined && x->complete == y->complete &&
           memcmp(x->point_a, y->point_a, sizeof x->point_a) == 0 &&
           memcmp(x->point_b, y->point_b, sizeof x->point_b) == 0 && x->tri_a == y->tri_a &&
           x->tri_b == y->tri_b &&
           memcmp(&x->sphere_distance, &y->sphere_distance, sizeof(double)) == 0;
}

/* The refined distance's batch: with the trees' meshes, chunks of 4 on 1 and 3 threads and on
 * all cores against a pair reset every 4 poses; trees without meshes and bad options refused. */
static void refined_batches(const char* dir, ist_tree* a, ist_tree* b, const ist_pose* pa,
                            const ist_pose* pb, size_t n) {
    ist_tree *am, *bm;
    with_meshes(dir, a, b, &am, &bm);
    ist_pair* pair = ist_pair_new(am, bm);
    ist_refined_distance_result* r = malloc(n * sizeof *r);
    const size_t threads[3] = {1, 3, 0};
    for (int t = 0; t < 3; t++) {
        CHECK(ist_refined_distance_many(am, bm, pa, n, pb, n, NULL, threads[t], 4, r) == IST_OK,
              "refined_distance_many");
        for (size_t i = 0; i < n; i++) {
            ist_refined_distance_result one;
            if (i % 4 == 0) ist_pair_reset(pair);
            CHECK(ist_refined_distance(pair, &pa[i], &pb[i], NULL, &one) == IST_OK, "refined");
            CHECK(same_refined(&r[i], &one), "refined_distance_many, pose %zu", i);
        }
    }
    CHECK(ist_refined_distance_many(a, b, pa, 1, pb, n, NULL, 0, 1, r) == IST_ERR_INVALID_ARGUMENT,
          "refined_distance_many without meshes");
    ist_refine_options bad = ist_refine_options_default();
    bad.radius_scale = NAN;
    CHECK(ist_refined_distance_many(am, bm, pa, 1, pb, n, &bad, 0, 1, r) == IST_ERR_INVALID_ARGUMENT,
          "refined_distance_many, NaN radius_scale");
    CHECK(ist_refined_distance_many(am, bm, pa, 1, pb, n, NULL, 0, 1, NULL) == IST_ERR_NULL,
          "refined_distance_many, NULL out");
    free(r);
    ist_pair_free(pair);
    ist_tree_free(am);
    ist_tree_free(bm);
}

/* The batches against single queries on a fresh pair (chunk 1), on 1 and 3 threads and on
 * all cores, with one pose of A for all and one each; a chunk of 5 equals a pair reset every
 * 5 poses; bad arguments are refused. Prints nothing (the single queries are diffed against
 * Rust above). */
static void batches(const char* dir, ist_tree* a, ist_tree* b) {
    char* path = join(dir, "poses.txt");
    FILE* f = fopen(path, "r");
    free(path);
    size_t n = 0, cap = 16;
    ist_pose* pa = malloc(cap * sizeof *pa);
    ist_pose* pb = malloc(cap * sizeof *pb);
    while (f && read_pose(f, &pa[n]) && read_pose(f, &pb[n])) {
        if (++n == cap) {
            cap *= 2;
            pa = realloc(pa, cap * sizeof *pa);
            pb = realloc(pb, cap * sizeof *pb);
        }
    }
    if (f) fclose(f);
    CHECK(n > 10, "%zu poses", n);
    double* d = malloc(n * sizeof *d);
    int* c = malloc(n * sizeof *c);
    ist_penetration_result* p = malloc(n * sizeof *p);
    ist_pair* pair = ist_pair_new(a, b);
    const size_t threads[3] = {1, 3, 0};
    for (int t = 0; t < 3; t++) {
        for (int each = 0; each < 2; each++) {
            size_t n_a = each ? n : 1;
            CHECK(ist_distance_many(a, b, pa, n_a, pb, n, threads[t], 1, d) == IST_OK, "distance_many");
            CHECK(ist_contact_many(a, b, pa, n_a, pb, n, threads[t], 1, c) == IST_OK, "contact_many");
            CHECK(ist_penetration_many(a, b, pa, n_a, pb, n, 2.5, threads[t], 1, p) == IST_OK,
                  "penetration_many");
            for (size_t i = 0; i < n; i++) {
                const ist_pose* x = each ? &pa[i] : &pa[0];
                ist_distance_result dr;
                ist_penetration_result pr;
                int in = -1;
                ist_pair_reset(pair);
                ist_distance(pair, x, &pb[i], &dr);
                ist_pair_reset(pair);
                ist_contact(pair, x, &pb[i], &in);
                ist_pair_reset(pair);
                ist_penetration_with_stiffness(pair, x, &pb[i], 2.5, &pr);
                CHECK(memcmp(&d[i], &dr.distance, sizeof(double)) == 0, "distance %zu", i);
                CHECK(c[i] == in, "contact %zu", i);
                CHECK(memcmp(&p[i], &pr, sizeof pr) == 0, "penetration %zu", i);
            }
        }
    }
    /* Chunks of 5: a pair reset every 5 poses. */
    CHECK(ist_penetration_many(a, b, pa, n, pb, n, 2.5, 2, 5, p) == IST_OK, "chunks of 5");
    for (size_t i = 0; i < n; i++) {
        ist_penetration_result pr;
        if (i % 5 == 0) ist_pair_reset(pair);
        ist_penetration_with_stiffness(pair, &pa[i], &pb[i], 2.5, &pr);
        CHECK(memcmp(&p[i], &pr, sizeof pr) == 0, "chunk of 5, pose %zu", i);
    }
    CHECK(ist_distance_many(a, b, pa, 2, pb, n, 0, 1, d) == IST_ERR_INVALID_ARGUMENT, "n_a 2");
    CHECK(ist_distance_many(a, b, pa, 1, pb, n, 0, 0, d) == IST_ERR_INVALID_ARGUMENT, "chunk 0");
    CHECK(ist_distance_many(a, b, pa, 1, pb, n, 0, 1, NULL) == IST_ERR_NULL, "NULL out");
    CHECK(ist_distance_many(a, b, NULL, 1, pb, n, 0, 1, d) == IST_ERR_NULL, "NULL poses_a");
    CHECK(ist_distance_many(NULL, b, pa, 1, pb, n, 0, 1, d) == IST_ERR_NULL, "NULL tree");
    CHECK(ist_distance_many(a, b, pa, 0, NULL, 0, 0, 1, NULL) == IST_OK, "an empty batch");
    ist_pose nan = pb[0];
    nan.t[0] = NAN;
    CHECK(ist_contact_many(a, b, pa, 1, &nan, 1, 0, 1, c) == IST_ERR_POSE, "NaN pose");
    CHECK(ist_penetration_many(a, b, pa, 1, pb, 1, 1e308, 0, 1, p) == IST_ERR_INVALID_ARGUMENT,
          "stiffness 1e308");
    ist_pair_free(pair);
    refined_batches(dir, a, b, pa, pb, n);
    free(pa);
    free(pb);
    free(d);
    free(c);
    free(p);
}

int main(int argc, char** argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s DIR (from `reference make DIR`)\n", argv[0]);
        return 2;
    }
    char* pa = join(argv[1], "a.ist");
    char* pb = join(argv[1], "b.ist");
    ist_tree* a = ist_tree_load(pa);
    ist_tree* b = ist_tree_load(pb);
    free(pa);
    free(pb);
    if (!a || !b) {
        fprintf(stderr, "loading the trees: %s\n", ist_last_error());
        return 1;
    }
    answers(argv[1], a, b);
    batches(argv[1], a, b);
    errors(argv[1], a, b);
    multirate(argv[1], a, b);
    /* A tree saved and loaded back answers the same. */
    char* again = join(argv[1], "again.ist");
    CHECK(ist_tree_save(a, again) == IST_OK, "save");
    ist_tree* a2 = ist_tree_load(again);
    CHECK(a2 != NULL && ist_tree_leaf_count(a2) == ist_tree_leaf_count(a), "reload");
    free(again);
    ist_tree_free(a2);
    ist_tree_free(a);
    ist_tree_free(b);
    if (failures) {
        fprintf(stderr, "%d checks failed\n", failures);
        return 1;
    }
    fprintf(stderr, "abi_test: all checks passed\n");
    return 0;
}
