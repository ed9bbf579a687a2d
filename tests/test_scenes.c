/* Tests of everything that turns input into a lanes_scene: the container,
 * mesh import (every format, node transforms), the JSON scene format, the
 * built-in scenes and lanes_scene_load, and a corpus of malformed inputs
 * that must each fail with a message naming the file (and the line, where
 * the format has lines), never crash.
 *
 *   test_scenes DATA SCRATCH            everything that needs no download
 *   test_scenes DATA SCRATCH --meshes   the CGAL meshes and the scenes made
 *                                       from them; exit 77 (skipped) when
 *                                       cmake/fetch_meshes.sh has not run
 *   test_scenes DATA SCRATCH --corpus   only the malformed inputs (quick
 *                                       enough to run under valgrind)
 *
 * DATA is tests/data; SCRATCH a writable directory for the binary files
 * generated here (binary STL/PLY/GLB are written by the test, so the
 * expected bytes are visible in this file). */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE /* wait4: a child's own peak memory */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "build/memory_limit.h"
#include "build/mesh_import.h"
#include "build/mesh_ops.h"
#include "build/scene.h"
#include "build/scene_file.h"
#include "build/scene_load.h"
#include "build/scenes_builtin.h"
#include "build/vec3.h"
#include "tests/harness.h"

static const char *g_data, *g_scratch;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static const char *data(const char *rel)
{
    static char buf[8][4096];
    static int k;
    char *b = buf[k++ & 7];
    snprintf(b, sizeof buf[0], "%s/%s", g_data, rel);
    return b;
}

static const char *scratch(const char *rel)
{
    static char buf[8][4096];
    static int k;
    char *b = buf[k++ & 7];
    snprintf(b, sizeof buf[0], "%s/%s", g_scratch, rel);
    return b;
}

static const char *base_name(const char *path)
{
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

/* The message must name the file and contain every expected fragment. */
static void check_message(const char *what, const char *path, const char *msg,
                          const char *const *expect)
{
    CHECK(strstr(msg, base_name(path)) != NULL, "%s: message does not name the file: %s", what,
          msg);
    for (int i = 0; expect[i]; i++)
        CHECK(strstr(msg, expect[i]) != NULL, "%s: message lacks '%s': %s", what, expect[i], msg);
}

static void put_f32(unsigned char *p, float f, bool big);
static void put_u32(unsigned char *p, uint32_t w, bool big);

static void write_file(const char *path, const void *bytes, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!CHECK(f != NULL, "cannot write %s", path))
        return;
    fwrite(bytes, 1, n, f);
    fclose(f);
}

static bool all_finite(const lanes_scene *s)
{
    for (size_t i = 0; i < 9 * s->triangle_count; i++)
        if (!isfinite(s->verts[i]))
            return false;
    return true;
}

static void mesh_bounds(const lanes_mesh *m, float mn[3], float mx[3])
{
    for (int a = 0; a < 3; a++) {
        mn[a] = INFINITY;
        mx[a] = -INFINITY;
    }
    for (size_t v = 0; v < m->vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            mn[a] = fminf(mn[a], m->positions[3 * v + a]);
            mx[a] = fmaxf(mx[a], m->positions[3 * v + a]);
        }
}

static bool near3(const float v[3], double x, double y, double z, double eps)
{
    return fabs(v[0] - x) <= eps && fabs(v[1] - y) <= eps && fabs(v[2] - z) <= eps;
}

/* ---- the container ---- */

static void test_container(void)
{
    lanes_scene s;
    lanes_error err;
    lanes_scene_init(&s);
    CHECK(s.triangle_count == 0 && s.verts == NULL && s.camera.width == 512, "init");
    lanes_material m;
    memset(&m, 0, sizeof m);
    strcpy(m.name, "a");
    uint32_t ia, ib;
    CHECK(lanes_scene_add_material(&s, &m, &ia, &err) == LANES_OK && ia == 0, "first material");
    CHECK(lanes_scene_add_material(&s, &m, &ib, &err) != LANES_OK && strstr(err.message, "twice"),
          "duplicate name refused: %s", err.message);
    strcpy(m.name, "b");
    m.kind = LANES_MAT_GLASS;
    m.ior = 1.5f;
    CHECK(lanes_scene_add_material(&s, &m, &ib, &err) == LANES_OK && ib == 1, "second material");
    /* Growth across many reallocations keeps every triangle. */
    for (int i = 0; i < 100000; i++) {
        float v[9] = {(float)i, 0, 0, (float)i + 1, 0, 0, (float)i, 1, 0};
        if (lanes_scene_add_triangle(&s, v, (uint32_t)(i & 1), &err) != LANES_OK) {
            CHECK(false, "add_triangle %d: %s", i, err.message);
            break;
        }
    }
    CHECK(s.triangle_count == 100000 && s.triangle_capacity >= 100000, "count %zu",
          s.triangle_count);
    CHECK(s.verts[9 * 77777] == 77777.0f && s.material_of[77777] == 1, "contents kept");
    size_t cap = s.triangle_capacity;
    CHECK(lanes_scene_reserve_triangles(&s, LANES_SCENE_MAX_TRIANGLES, &err) != LANES_OK &&
              strstr(err.message, "too many"),
          "over the limit refused: %s", err.message);
    CHECK(lanes_scene_reserve_triangles(&s, SIZE_MAX, &err) != LANES_OK, "SIZE_MAX refused");
    /* Under the count limit but beyond memory: refused before allocating. */
    CHECK(lanes_memory_fits("one byte", 1.0, NULL) == LANES_OK, "one byte fits");
    CHECK(lanes_memory_fits("an exabyte", 1e18, &err) != LANES_OK &&
              strstr(err.message, "an exabyte needs about") && strstr(err.message, "of memory"),
          "an exabyte refused: %s", err.message);
    /* The loaders apply the memory policy; a scene built by hand gets it
     * when it asks. */
    CHECK(lanes_scene_limit_to_memory(&s, &err) == LANES_OK && s.triangle_budget > s.triangle_count,
          "memory budget: %s", err.message);
    size_t most = LANES_SCENE_MAX_TRIANGLES - s.triangle_count;
    double most_bytes = (double)LANES_SCENE_MAX_TRIANGLES *
                        (double)(LANES_SCENE_BYTES_PER_TRIANGLE + LANES_ACCEL_BYTES_PER_TRIANGLE);
    if (lanes_memory_fits("", most_bytes, NULL) == LANES_OK) {
        printf("skip: this machine holds %.0f GiB, enough for 2^31 triangles\n", most_bytes / 1073741824.0);
    } else {
        CHECK(lanes_scene_reserve_triangles(&s, most, &err) != LANES_OK &&
                  strstr(err.message, "to load and trace"),
              "2^31 triangles on this machine refused for memory: %s", err.message);
    }
    CHECK(s.triangle_capacity == cap && s.triangle_count == 100000, "unchanged after refusal");
    lanes_point_light pl = {{0, 5, 0}, {1, 1, 1}};
    CHECK(lanes_scene_add_point_light(&s, &pl, &err) == LANES_OK, "point light");
    CHECK(lanes_scene_validate(&s, &err) == LANES_OK, "valid: %s", err.message);
    float mn[3], mx[3];
    s.verts[4] = NAN;
    lanes_scene_bounds(&s, mn, mx);
    CHECK(mn[0] == 0.0f && mx[0] == 100000.0f && isfinite(mn[1]) && isfinite(mx[1]),
          "bounds skip NaN");
    CHECK(lanes_scene_validate(&s, &err) != LANES_OK && strstr(err.message, "non-finite"), "NaN caught");
    s.verts[4] = 0.0f;
    s.material_of[5] = 7;
    CHECK(lanes_scene_validate(&s, &err) != LANES_OK && strstr(err.message, "material"),
          "bad material index caught: %s", err.message);
    s.material_of[5] = 0;
    s.camera.up[0] = s.camera.up[2] = 0.0f;
    s.camera.eye[0] = s.camera.eye[2] = 0.0f;
    s.camera.eye[1] = 5.0f;
    s.camera.target[0] = s.camera.target[1] = s.camera.target[2] = 0.0f;
    CHECK(lanes_scene_validate(&s, &err) != LANES_OK && strstr(err.message, "camera"),
          "up parallel to view caught: %s", err.message);
    lanes_scene_free(&s);
    lanes_scene_free(&s); /* twice is harmless */
    CHECK(s.verts == NULL && s.triangle_count == 0, "freed");

    /* Transforms: a rotation of +90 degrees about y takes +x to -z. */
    lanes_xform r, x;
    const double up[3] = {0, 1, 0}, t[3] = {1, 2, 3}, sc[3] = {2, 2, 2};
    lanes_xform_rotation(&r, up, 90.0);
    float in[3] = {1, 0, 0}, out[3];
    lanes_xform_apply(&r, in, out);
    CHECK(near3(out, 0, 0, -1, 1e-6), "rotation: %g %g %g", out[0], out[1], out[2]);
    lanes_xform_trs(&x, t, &r, sc); /* scale, then rotate, then translate */
    lanes_xform_apply(&x, in, out);
    CHECK(near3(out, 1, 2, 1, 1e-6), "trs: %g %g %g", out[0], out[1], out[2]);
}

/* ---- the memory limit ---- */

static void put_text(const char *dir, const char *name, const char *text)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    write_file(path, text, strlen(text));
}

static void make_dirs(const char *root, const char *rel)
{
    char path[1024];
    int n = snprintf(path, sizeof path, "%s/%s", root, rel);
    for (int i = 1; i <= n; i++)
        if (path[i] == '/' || path[i] == '\0') {
            char c = path[i];
            path[i] = '\0';
            mkdir(path, 0755);
            path[i] = c;
        }
}

/* A cgroup tree of our own: the limits are read from the cgroup and every
 * ancestor, v2 and v1, and the smallest of them and physical memory wins. */
static void test_memory_limit(void)
{
    const double gib = 1073741824.0, physical = 16 * gib;
    char root[512], proc[512], sub[768];
    snprintf(root, sizeof root, "%s/cgroup", g_scratch);
    snprintf(proc, sizeof proc, "%s/proc_self_cgroup", g_scratch);
    make_dirs(root, "v2/outer/inner");
    make_dirs(root, "v1/memory/job/step");
    make_dirs(root, "v1/cpu,cpuacct/job");

    /* v2: the parent's 1 GiB binds the unlimited child */
    put_text(g_scratch, "proc_self_cgroup", "0::/outer/inner\n");
    snprintf(sub, sizeof sub, "%s/v2", root);
    put_text(sub, "outer/inner/memory.max", "max\n");
    put_text(sub, "outer/memory.max", "1073741824\n");
    lanes_memory_limit l = lanes_memory_limit_from(proc, sub, physical);
    CHECK(l.bytes == gib && l.source == LANES_MEMORY_CGROUP, "v2 parent limit: %.0f bytes", l.bytes);
    put_text(sub, "outer/memory.max", "max\n");
    l = lanes_memory_limit_from(proc, sub, physical);
    CHECK(l.bytes == physical && l.source == LANES_MEMORY_PHYSICAL, "v2 unlimited: have %.0f", l.bytes);
    put_text(sub, "outer/memory.max", "68719476736\n"); /* 64 GiB: above physical memory */
    l = lanes_memory_limit_from(proc, sub, physical);
    CHECK(l.bytes == physical && l.source == LANES_MEMORY_PHYSICAL, "v2 limit above physical: have %.0f",
          l.bytes);
    put_text(sub, "outer/memory.max", "12abc\n");
    l = lanes_memory_limit_from(proc, sub, physical);
    CHECK(l.bytes == physical, "v2 unreadable limit ignored: have %.0f", l.bytes);

    /* v1: only the memory hierarchy counts; its "unlimited" is a huge count */
    put_text(g_scratch, "proc_self_cgroup", "5:cpu,cpuacct:/job\n4:memory:/job/step\n0::/\n");
    snprintf(sub, sizeof sub, "%s/v1", root);
    put_text(sub, "cpu,cpuacct/job/memory.limit_in_bytes", "1024\n");
    put_text(sub, "memory/memory.limit_in_bytes", "9223372036854771712\n");
    put_text(sub, "memory/job/memory.limit_in_bytes", "9223372036854771712\n");
    put_text(sub, "memory/job/step/memory.limit_in_bytes", "2147483648\n");
    l = lanes_memory_limit_from(proc, sub, physical);
    CHECK(l.bytes == 2 * gib && l.source == LANES_MEMORY_CGROUP, "v1 limit: %.0f bytes", l.bytes);

    /* no cgroup files at all: physical memory */
    snprintf(sub, sizeof sub, "%s/none", root);
    l = lanes_memory_limit_from(proc, sub, physical);
    CHECK(l.bytes == physical && l.source == LANES_MEMORY_PHYSICAL, "no cgroup files: have %.0f", l.bytes);
    snprintf(sub, sizeof sub, "%s/no_such_file", g_scratch);
    l = lanes_memory_limit_from(sub, root, physical);
    CHECK(l.bytes == physical && l.source == LANES_MEMORY_PHYSICAL, "no /proc/self/cgroup: have %.0f", l.bytes);

    /* LANES_MEMORY_LIMIT */
    static const struct {
        const char *text;
        double bytes; /* 0: refused */
    } sizes[] = {{"1024", 1024.0}, {"4G", 4 * gib}, {"1.5m", 1.5 * 1048576.0}, {"640k", 655360.0},
                 {"", 0}, {"-1", 0}, {"0", 0}, {"12x", 0}, {"G", 0}, {"4GB", 0}, {"nan", 0}, {"1e999", 0}};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        double bytes = 0;
        bool ok = lanes_memory_size_parse(sizes[i].text, &bytes);
        CHECK(ok == (sizes[i].bytes > 0) && (!ok || bytes == sizes[i].bytes), "size '%s': %s %.0f", sizes[i].text,
              ok ? "read as" : "refused", bytes);
    }

    /* A scene is checked at every count, not only when its arrays grow:
     * three icospheres of 81,920 triangles grow the arrays to 131,072 and
     * then 262,144 slots, so the third sphere needs no growth, and only a
     * check at every count sees 245,760 triangles. */
    const double per_triangle = (double)(LANES_SCENE_BYTES_PER_TRIANGLE + LANES_ACCEL_BYTES_PER_TRIANGLE);
    char limit[32], two[512], three[512];
    snprintf(limit, sizeof limit, "%.0f", 200000.0 * per_triangle);
    snprintf(two, sizeof two, "%s/two_spheres.json", g_scratch);
    snprintf(three, sizeof three, "%s/three_spheres.json", g_scratch);
    const char *head = "{\"materials\": {\"m\": {\"type\": \"diffuse\", \"color\": 0.5}}, \"objects\": [";
    const char *sphere = "{\"builtin\": \"sphere\", \"detail\": 6, \"material\": \"m\"}";
    char text[512];
    snprintf(text, sizeof text, "%s%s, %s]}", head, sphere, sphere);
    write_file(two, text, strlen(text));
    snprintf(text, sizeof text, "%s%s, %s, %s]}", head, sphere, sphere, sphere);
    write_file(three, text, strlen(text));
    setenv("LANES_MEMORY_LIMIT", limit, 1);
    lanes_scene s;
    lanes_error err;
    bool loaded = lanes_scene_load(two, &s, &err) == LANES_OK;
    CHECK(loaded && s.triangle_count == 163840, "two spheres under LANES_MEMORY_LIMIT=%s: %s", limit,
          loaded ? "loaded" : err.message);
    if (loaded) lanes_scene_free(&s);
    /* the status travels up from where the failure was found (the scene's
     * budget inside the file loader) with it, as the public API hands it on */
    lanes_status st = lanes_scene_load(three, &s, &err);
    loaded = st == LANES_OK;
    CHECK(!loaded && strstr(err.message, "three_spheres.json") && strstr(err.message, "245760 triangles") &&
              strstr(err.message, "LANES_MEMORY_LIMIT allows"),
          "three spheres over LANES_MEMORY_LIMIT=%s: %s", limit, loaded ? "loaded" : err.message);
    CHECK(st == LANES_ERR_OUT_OF_MEMORY && err.status == st, "three spheres over the limit: status %s, err.status %s",
          lanes_status_name(st), lanes_status_name(err.status));
    if (loaded) lanes_scene_free(&s);
    setenv("LANES_MEMORY_LIMIT", "lots", 1);
    st = lanes_scene_load(two, &s, &err);
    loaded = st == LANES_OK;
    CHECK(!loaded && strstr(err.message, "LANES_MEMORY_LIMIT 'lots' is not a size"), "LANES_MEMORY_LIMIT=lots: %s",
          loaded ? "loaded" : err.message);
    CHECK(st == LANES_ERR_BAD_INPUT && err.status == st, "LANES_MEMORY_LIMIT=lots: status %s, err.status %s",
          lanes_status_name(st), lanes_status_name(err.status));
    if (loaded) lanes_scene_free(&s);

    /* The import's own memory counts vertices too: a binary PLY of 1M
     * vertices and one face needs some 46 MB inside Assimp though its scene
     * is one triangle, and is refused before Assimp reads it. */
    char sparse[512];
    snprintf(sparse, sizeof sparse, "%s/sparse.ply", g_scratch);
    {
        enum { NV = 1000000 };
        char hdr[256];
        int hn = snprintf(hdr, sizeof hdr,
                          "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
                          "property float y\nproperty float z\nelement face 1\n"
                          "property list uchar int vertex_indices\nend_header\n",
                          NV);
        size_t bytes = (size_t)hn + (size_t)NV * 12 + 13;
        unsigned char *buf = calloc(1, bytes);
        memcpy(buf, hdr, (size_t)hn);
        for (int i = 0; i < NV; i++) put_f32(buf + hn + 12 * i, (float)i, false); /* x = i: distinct */
        unsigned char *f = buf + hn + (size_t)NV * 12;
        f[0] = 3;
        put_u32(f + 1, 0, false), put_u32(f + 5, 1, false), put_u32(f + 9, 2, false);
        write_file(sparse, buf, bytes);
        free(buf);
    }
    setenv("LANES_MEMORY_LIMIT", "20M", 1);
    lanes_mesh m;
    st = lanes_mesh_read(sparse, &m, &err);
    CHECK(st == LANES_ERR_OUT_OF_MEMORY && strstr(err.message, "importing 1000000 vertices and 1 faces") &&
              strstr(err.message, "LANES_MEMORY_LIMIT allows"),
          "sparse PLY over LANES_MEMORY_LIMIT=20M: status %s: %s", lanes_status_name(st),
          st == LANES_OK ? "loaded" : err.message);
    if (st == LANES_OK) lanes_mesh_free(&m);
    unsetenv("LANES_MEMORY_LIMIT");
    st = lanes_mesh_read(sparse, &m, &err);
    CHECK(st == LANES_OK && m.triangle_count == 1, "sparse PLY without a limit: %s",
          st == LANES_OK ? "wrong triangle count" : err.message);
    if (st == LANES_OK) lanes_mesh_free(&m);

    /* The running count still refuses a scene that declared less than it
     * makes (polygons triangulate to more triangles than faces): adding
     * meshes one by one to a scene on a budget fails at the mesh that
     * crosses it, whatever the arrays' capacity. */
    setenv("LANES_MEMORY_LIMIT", limit, 1);
    lanes_scene direct;
    lanes_scene_init(&direct);
    lanes_mesh sph;
    CHECK(lanes_scene_limit_to_memory(&direct, &err) == LANES_OK &&
              lanes_builtin_object("sphere", 6, &sph, &err) == LANES_OK,
          "budget and sphere: %s", err.message);
    lanes_xform ident;
    lanes_xform_identity(&ident);
    lanes_material grey;
    memset(&grey, 0, sizeof grey);
    strcpy(grey.name, "grey");
    uint32_t grey_index;
    CHECK(lanes_scene_add_material(&direct, &grey, &grey_index, &err) == LANES_OK, "material: %s", err.message);
    int added = 0;
    for (int k = 0; k < 3; k++) {
        if (lanes_scene_add_mesh(&direct, &sph, &ident, grey_index, "sphere", &err) != LANES_OK) break;
        added++;
    }
    CHECK(added == 2 && err.status == LANES_ERR_OUT_OF_MEMORY && strstr(err.message, "245760 triangles"),
          "spheres added one by one under LANES_MEMORY_LIMIT=%s: %d added; %s", limit, added, err.message);
    lanes_mesh_free(&sph);
    lanes_scene_free(&direct);
    unsetenv("LANES_MEMORY_LIMIT");

    /* this process: something positive */
    l = lanes_memory_limit_read();
    printf("this process may use %.1f GiB (%s)\n", l.bytes / gib,
           l.source == LANES_MEMORY_CGROUP ? "cgroup limit" : "physical memory");
    CHECK(l.bytes > 0, "this process's memory limit: %.0f", l.bytes);
}

/* ---- memory ceilings ---- */

/* One load in a child process, so that its peak memory is its own: the
 * child's resident high-water mark (wait4) less that of a child that loads
 * nothing. The status and message come back through a pipe. */
typedef struct child_load {
    lanes_status status;
    char message[512];
    double peak_growth; /* bytes */
} child_load;

static double child_peak(const char *path, const char *limit, bool mesh_only, child_load *out)
{
    int fd[2];
    if (pipe(fd) != 0) return -1;
    pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        child_load r = {LANES_OK, "", 0};
        if (path) {
            if (limit) setenv("LANES_MEMORY_LIMIT", limit, 1);
            lanes_error err = {0};
            if (mesh_only) {
                lanes_mesh m;
                if ((r.status = lanes_mesh_read(path, &m, &err)) == LANES_OK) lanes_mesh_free(&m);
            } else {
                lanes_scene sc;
                if ((r.status = lanes_scene_load(path, &sc, &err)) == LANES_OK) lanes_scene_free(&sc);
            }
            snprintf(r.message, sizeof r.message, "%s", r.status == LANES_OK ? "loaded" : err.message);
        }
        ssize_t w = write(fd[1], &r, sizeof r);
        _exit(w == (ssize_t)sizeof r ? 0 : 1);
    }
    close(fd[1]);
    ssize_t got = pid > 0 ? read(fd[0], out, sizeof *out) : -1;
    close(fd[0]);
    int wstatus = 0;
    struct rusage ru;
    if (pid <= 0 || wait4(pid, &wstatus, 0, &ru) != pid || got != (ssize_t)sizeof *out || !WIFEXITED(wstatus))
        return -1;
    return (double)ru.ru_maxrss * 1024.0;
}

/* Every load stays under twice its bound: a load under LANES_MEMORY_LIMIT
 * (succeeding or refused) peaks below twice the limit, and a scene refused
 * from its declared size peaks at what parsing its file takes, having made
 * nothing. */
static void test_load_ceilings(void)
{
    child_load base, r;
    double baseline = child_peak(NULL, NULL, false, &base);
    CHECK(baseline > 0, "a child process's baseline peak");
    if (baseline <= 0) return;

    const char *head = "{\"materials\": {\"m\": {\"type\": \"diffuse\", \"color\": 0.5}}, \"objects\": [";
    const char *sphere8 = "{\"builtin\": \"sphere\", \"detail\": 8, \"material\": \"m\"}";
    size_t cap = strlen(head) + 200 * (strlen(sphere8) + 2) + 4;
    char *text = malloc(cap), *many = strdup(scratch("spheres_200_detail_8.json"));
    size_t len = (size_t)snprintf(text, cap, "%s", head);
    for (int i = 0; i < 200; i++) len += (size_t)snprintf(text + len, cap - len, "%s%s", i ? ", " : "", sphere8);
    len += (size_t)snprintf(text + len, cap - len, "]}");
    write_file(many, text, len);
    free(text);

    const double per_triangle = (double)(LANES_SCENE_BYTES_PER_TRIANGLE + LANES_ACCEL_BYTES_PER_TRIANGLE);
    char small[32];
    snprintf(small, sizeof small, "%.0f", 200000.0 * per_triangle);
    const struct {
        const char *path, *limit;
        bool mesh_only;
        lanes_status want;
        const char *needle;
        double ceiling; /* bytes over the baseline */
    } cases[] = {
        /* 262,144,000 triangles declared: about 76 GiB, refused at once */
        {many, "16G", false, LANES_ERR_OUT_OF_MEMORY, "declare 262144000 triangles", 64e6},
        {scratch("two_spheres.json"), small, false, LANES_OK, "loaded", 2 * 200000.0 * per_triangle},
        {scratch("three_spheres.json"), small, false, LANES_ERR_OUT_OF_MEMORY, "declare 245760 triangles",
         2 * 200000.0 * per_triangle},
        {scratch("sparse.ply"), "20M", true, LANES_ERR_OUT_OF_MEMORY, "importing 1000000 vertices", 2 * 20e6},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double start = now();
        double peak = child_peak(cases[i].path, cases[i].limit, cases[i].mesh_only, &r);
        double seconds = now() - start, growth = peak - baseline;
        const char *name = strrchr(cases[i].path, '/') + 1;
        CHECK(peak > 0 && r.status == cases[i].want && strstr(r.message, cases[i].needle),
              "%s under LANES_MEMORY_LIMIT=%s: status %s: %s", name, cases[i].limit, lanes_status_name(r.status),
              r.message);
        CHECK(peak > 0 && growth <= cases[i].ceiling, "%s under LANES_MEMORY_LIMIT=%s peaked %.1f MB over the "
              "baseline; its ceiling is %.1f MB", name, cases[i].limit, growth / 1e6, cases[i].ceiling / 1e6);
        printf("%s under LANES_MEMORY_LIMIT=%s: %s in %.2f s, peak %.1f MB over the baseline (ceiling %.1f MB)\n",
               name, cases[i].limit, lanes_status_name(r.status), seconds, growth / 1e6, cases[i].ceiling / 1e6);
    }
    free(many);
}

/* ---- mesh import ---- */

typedef struct expect_mesh {
    const char *path;
    size_t triangles, vertices;
    float min[3], max[3];
} expect_mesh;

static void check_mesh_file(const char *path, size_t tris, size_t verts, const float mn_e[3],
                            const float mx_e[3])
{
    lanes_mesh m;
    lanes_error err;
    if (!CHECK(lanes_mesh_read(path, &m, &err) == LANES_OK, "%s: %s", path, err.message)) return;
    CHECK(m.triangle_count == tris, "%s: %zu triangles, expected %zu", path, m.triangle_count,
          tris);
    CHECK(m.vertex_count == verts, "%s: %zu vertices, expected %zu", path, m.vertex_count, verts);
    for (size_t i = 0; i < 3 * m.triangle_count; i++)
        if (!CHECK(m.indices[i] < m.vertex_count, "%s: index out of range", path))
            break;
    float mn[3], mx[3];
    mesh_bounds(&m, mn, mx);
    CHECK(near3(mn, mn_e[0], mn_e[1], mn_e[2], 1e-6) && near3(mx, mx_e[0], mx_e[1], mx_e[2], 1e-6),
          "%s: bounds [%g %g %g]-[%g %g %g]", path, mn[0], mn[1], mn[2], mx[0], mx[1], mx[2]);
    lanes_mesh_free(&m);
}

static void put_f32(unsigned char *p, float f, bool big)
{
    uint32_t w;
    memcpy(&w, &f, 4);
    for (int i = 0; i < 4; i++)
        p[big ? 3 - i : i] = (unsigned char)(w >> (8 * i));
}

static void put_u32(unsigned char *p, uint32_t w, bool big)
{
    for (int i = 0; i < 4; i++)
        p[big ? 3 - i : i] = (unsigned char)(w >> (8 * i));
}

static const float tet_v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
static const int tet_f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

/* Binary PLY of the tetrahedron; `bad_index` replaces the last index,
 * `faces_written` < 4 truncates. */
static void write_ply_bin(const char *path, bool big, int bad_index, int faces_written)
{
    char head[256];
    int n = snprintf(head, sizeof head,
                     "ply\nformat %s 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                     "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                     "end_header\n",
                     big ? "binary_big_endian" : "binary_little_endian");
    unsigned char buf[512];
    memcpy(buf, head, (size_t)n);
    unsigned char *p = buf + n;
    for (int v = 0; v < 4; v++)
        for (int a = 0; a < 3; a++, p += 4)
            put_f32(p, tet_v[v][a], big);
    for (int f = 0; f < faces_written; f++) {
        *p++ = 3;
        for (int k = 0; k < 3; k++, p += 4)
            put_u32(p, (uint32_t)(f == 3 && k == 2 && bad_index ? bad_index : tet_f[f][k]), big);
    }
    write_file(path, buf, (size_t)(p - buf));
}

static void write_stl_bin(const char *path, uint32_t declared, int written, bool nan)
{
    unsigned char buf[84 + 50 * 4];
    memset(buf, 0, sizeof buf);
    memcpy(buf, "binary STL written by test_scenes.c", 35);
    put_u32(buf + 80, declared, false);
    for (int f = 0; f < written; f++) {
        unsigned char *r = buf + 84 + 50 * f;
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++)
                put_f32(r + 12 + 12 * k + 4 * a,
                        nan && f == 1 && k == 2 ? NAN : tet_v[tet_f[f][k]][a], false);
    }
    write_file(path, buf, 84 + 50 * (size_t)written);
}

/* A GLB: one triangle, node translation (0, 0, 5). */
static void write_glb(const char *path, size_t cut)
{
    static const char json[] =
        "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
        "\"nodes\":[{\"mesh\":0,\"translation\":[0,0,5]}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"buffers\":[{\"byteLength\":44}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
        "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
        "\"min\":[0,0,0],\"max\":[1,1,0]},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]}";
    size_t jl = (sizeof json - 1 + 3) & ~(size_t)3;
    unsigned char buf[2048];
    memset(buf, ' ', sizeof buf);
    size_t total = 12 + 8 + jl + 8 + 44;
    put_u32(buf, 0x46546C67u, false);
    put_u32(buf + 4, 2, false);
    put_u32(buf + 8, (uint32_t)total, false);
    put_u32(buf + 12, (uint32_t)jl, false);
    put_u32(buf + 16, 0x4E4F534Au, false);
    memcpy(buf + 20, json, sizeof json - 1);
    unsigned char *b = buf + 20 + jl;
    put_u32(b, 44, false);
    put_u32(b + 4, 0x004E4942u, false);
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    for (int i = 0; i < 9; i++)
        put_f32(b + 8 + 4 * i, pos[i], false);
    const unsigned char idx[8] = {0, 0, 1, 0, 2, 0, 0, 0};
    memcpy(b + 8 + 36, idx, 8);
    write_file(path, buf, total - cut);
}

static void test_mesh_formats(void)
{
    const float z3[3] = {0, 0, 0}, one[3] = {1, 1, 1}, unit_xy[3] = {1, 1, 0}, two[3] = {2, 2, 0};
    check_mesh_file(data("meshes/ok/quad.obj"), 2, 4, z3, unit_xy);
    check_mesh_file(data("meshes/ok/mixed.obj"), 3, 4, z3, one);
    check_mesh_file(data("meshes/ok/tet.off"), 4, 4, z3, one);
    check_mesh_file(data("meshes/ok/quad.off"), 2, 4, z3, two);
    check_mesh_file(data("meshes/ok/tet.ply"), 4, 4, z3, one);
    check_mesh_file(data("meshes/ok/tet.stl"), 4, 4, z3, one);
    /* keywords in upper case (Assimp matches them in lower case only) */
    check_mesh_file(data("meshes/ok/tet_upper.stl"), 4, 4, z3, one);
    /* backslash continuations, joined as Assimp joins them */
    check_mesh_file(data("meshes/ok/continued.obj"), 2, 4, z3, unit_xy);
    /* mtllib names this file and one elsewhere; neither is read */
    check_mesh_file(data("meshes/ok/mtllib.obj"), 2, 4, z3, unit_xy);
    /* Node transforms: the root translates by (10,0,0) and holds the
     * triangle; its child scales by 2 and holds it again, so the child's
     * copy is scaled first, then translated. */
    const float n_mn[3] = {10, 0, 0}, n_mx[3] = {12, 2, 0};
    check_mesh_file(data("meshes/ok/nodes.gltf"), 2, 5, n_mn, n_mx);
    write_ply_bin(scratch("tet_le.ply"), false, 0, 4);
    write_ply_bin(scratch("tet_be.ply"), true, 0, 4);
    write_stl_bin(scratch("tet_bin.stl"), 4, 4, false);
    write_glb(scratch("tri.glb"), 0);
    check_mesh_file(scratch("tet_le.ply"), 4, 4, z3, one);
    check_mesh_file(scratch("tet_be.ply"), 4, 4, z3, one);
    check_mesh_file(scratch("tet_bin.stl"), 4, 4, z3, one);
    const float g_mn[3] = {0, 0, 5}, g_mx[3] = {1, 1, 5};
    check_mesh_file(scratch("tri.glb"), 1, 3, g_mn, g_mx);

    /* The extra transform and the material of lanes_mesh_import. */
    lanes_scene s;
    lanes_error err;
    lanes_scene_init(&s);
    lanes_material m;
    memset(&m, 0, sizeof m);
    strcpy(m.name, "x");
    uint32_t mi;
    lanes_scene_add_material(&s, &m, NULL, &err);
    strcpy(m.name, "y");
    lanes_scene_add_material(&s, &m, &mi, &err);
    lanes_xform x;
    const double t[3] = {0, 0, -3}, sc[3] = {3, 3, 3};
    lanes_xform_trs(&x, t, NULL, sc);
    if (CHECK(lanes_mesh_import(&s, data("meshes/ok/quad.obj"), &x, mi, &err) == LANES_OK, "%s",
              err.message)) {
        float mn[3], mx[3];
        lanes_scene_bounds(&s, mn, mx);
        CHECK(s.triangle_count == 2 && s.material_of[0] == 1 && s.material_of[1] == 1,
              "material index");
        CHECK(near3(mn, 0, 0, -3, 1e-6) && near3(mx, 3, 3, -3, 1e-6), "extra transform");
    }
    CHECK(lanes_mesh_import(&s, data("meshes/ok/quad.obj"), NULL, 9, &err) != LANES_OK &&
              s.triangle_count == 2,
          "undefined material index refused, scene unchanged");
    lanes_scene_free(&s);
}

/* ---- generated geometry ---- */

static void test_generators(void)
{
    lanes_mesh m, f;
    lanes_error err;
    struct {
        const char *name;
        int detail;
        size_t tris;
    } prims[] = {{"sphere", 0, 20}, {"sphere", -1, 1280}, {"box", -1, 12},
                 {"plane", -1, 2},  {"plane", 4, 32},     {"cylinder", -1, 128}};
    for (size_t i = 0; i < sizeof prims / sizeof prims[0]; i++) {
        if (!CHECK(lanes_builtin_object(prims[i].name, prims[i].detail, &m, &err) == LANES_OK, "%s",
                   err.message))
            continue;
        CHECK(m.triangle_count == prims[i].tris, "%s detail %d: %zu triangles", prims[i].name,
              prims[i].detail, m.triangle_count);
        float mn[3], mx[3];
        mesh_bounds(&m, mn, mx);
        CHECK(mn[0] >= -1.0f && mx[0] <= 1.0f && mn[1] >= -1.0f && mx[1] <= 1.0f &&
                  mn[2] >= -1.0f && mx[2] <= 1.0f,
              "%s fits [-1,1]^3", prims[i].name);
        if (strcmp(prims[i].name, "sphere") == 0) {
            for (size_t v = 0; v < m.vertex_count; v++) {
                const float *p = m.positions + 3 * v;
                if (!CHECK(fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1.0) < 1e-6,
                           "sphere vertex %zu off the unit sphere", v))
                    break;
            }
            /* Closed: V - E + F = 2 with E = 3F/2. */
            CHECK(m.vertex_count - m.triangle_count / 2 == 2, "sphere Euler characteristic");
        }
        lanes_mesh_free(&m);
    }
    CHECK(lanes_builtin_object("teapot", -1, &m, &err) != LANES_OK && strstr(err.message, "valid"),
          "unknown object: %s", err.message);

    /* Loop subdivision of a tetrahedron: V + E vertices, 4F triangles. */
    float pos[12];
    uint32_t idx[12];
    for (int v = 0; v < 4; v++)
        memcpy(pos + 3 * v, tet_v[v], sizeof tet_v[v]);
    for (int t = 0; t < 4; t++)
        for (int k = 0; k < 3; k++)
            idx[3 * t + k] = (uint32_t)tet_f[t][k];
    lanes_mesh tet = {pos, idx, 4, 4};
    if (CHECK(lanes_mesh_subdivide(&tet, &f, &err) == LANES_OK, "%s", err.message)) {
        CHECK(f.vertex_count == 10 && f.triangle_count == 16, "subdivided tet: %zu V %zu F",
              f.vertex_count, f.triangle_count);
        float mn[3], mx[3];
        mesh_bounds(&f, mn, mx);
        /* Smoothing pulls the surface inside the control hull. */
        CHECK(mn[0] >= 0.0f && mx[0] < 1.0f && mx[0] > 0.3f, "smoothed inside the hull");
        lanes_mesh_free(&f);
    }
    if (CHECK(lanes_builtin_object("sphere", 5, &m, &err) == LANES_OK, "%s", err.message)) {
        if (CHECK(lanes_mesh_decimate(&m, 8, &f, &err) == LANES_OK, "%s", err.message)) {
            CHECK(f.triangle_count > 20 && f.triangle_count < m.triangle_count / 10,
                  "decimated %zu -> %zu", m.triangle_count, f.triangle_count);
            for (size_t i = 0; i < 3 * f.triangle_count; i++)
                if (!CHECK(f.indices[i] < f.vertex_count, "decimated index"))
                    break;
            lanes_mesh_free(&f);
        }
        lanes_mesh_free(&m);
    }
}

/* ---- built-in scenes ---- */

typedef struct scene_expect {
    const char *name;
    size_t min_tris, max_tris;
    bool needs_meshes;
} scene_expect;

static size_t count_kind(const lanes_scene *s, lanes_material_kind k)
{
    size_t n = 0;
    for (size_t i = 0; i < s->triangle_count; i++)
        n += s->materials[s->material_of[i]].kind == k;
    return n;
}

static void check_builtin(const scene_expect *e)
{
    lanes_scene s, again;
    lanes_error err;
    double t0 = now();
    if (!CHECK(lanes_scene_load(e->name, &s, &err) == LANES_OK, "%s: %s", e->name, err.message)) return;
    double dt = now() - t0;
    printf("  %-18s %9zu triangles  %zu materials  %zu point + %zu area lights  %.3f s\n", e->name,
           s.triangle_count, s.material_count, s.point_light_count, s.area_light_count, dt);
    CHECK(s.triangle_count >= e->min_tris && s.triangle_count <= e->max_tris,
          "%s: %zu triangles outside [%zu, %zu]", e->name, s.triangle_count, e->min_tris,
          e->max_tris);
    CHECK(lanes_scene_validate(&s, &err) == LANES_OK, "%s: %s", e->name, err.message);
    CHECK(all_finite(&s), "%s: non-finite vertex", e->name);
    CHECK(strcmp(s.name, e->name) == 0, "%s: name '%s'", e->name, s.name);
    CHECK(s.point_light_count + s.area_light_count >= 1, "%s: no light", e->name);
    float mn[3], mx[3];
    lanes_scene_bounds(&s, mn, mx);
    bool sane = true;
    for (int a = 0; a < 3; a++)
        sane = sane && isfinite(mn[a]) && isfinite(mx[a]) && mn[a] <= mx[a] && mx[a] - mn[a] < 1e3;
    CHECK(sane, "%s: bounds [%g %g %g]-[%g %g %g]", e->name, mn[0], mn[1], mn[2], mx[0], mx[1],
          mx[2]);
    /* The camera looks at the scene from outside its geometry's middle. */
    bool target_inside = true;
    for (int a = 0; a < 3; a++)
        target_inside = target_inside && s.camera.target[a] >= mn[a] - 1e-3f &&
                        s.camera.target[a] <= mx[a] + 1e-3f;
    CHECK(target_inside, "%s: camera target outside the bounds", e->name);
    /* What the thesis' Table 4.1 says each scene is made of. */
    size_t mirror = count_kind(&s, LANES_MAT_MIRROR), glass = count_kind(&s, LANES_MAT_GLASS);
    if (strcmp(e->name, "dragon") == 0)
        CHECK(mirror == 0 && glass == 0, "dragon must be fully diffuse");
    if (strncmp(e->name, "hairball", 8) == 0)
        CHECK(mirror == s.triangle_count, "hairball must be all mirror");
    if (strcmp(e->name, "sponza-bunny") == 0)
        CHECK(mirror == 75408, "sponza: only the bunny is mirror (%zu)", mirror);
    if (strncmp(e->name, "20-bunnies", 10) == 0)
        CHECK(mirror > 0 && mirror * 2 > s.triangle_count - 10 &&
                  mirror * 2 < s.triangle_count + 10,
              "20-bunnies: half the bunnies mirror (%zu of %zu)", mirror, s.triangle_count);
    if (strcmp(e->name, "default") == 0)
        CHECK(mirror > 0 && glass > 0 && count_kind(&s, LANES_MAT_EMISSIVE) == 2 &&
                  s.area_light_count == 1 && s.point_light_count == 1,
              "default: mirror, glass, an area light and a point light");
    /* Deterministic: the same bytes every time. */
    if (CHECK(lanes_scene_load(e->name, &again, &err) == LANES_OK, "%s again: %s", e->name, err.message)) {
        CHECK(again.triangle_count == s.triangle_count &&
                  memcmp(again.verts, s.verts, 9 * sizeof(float) * s.triangle_count) == 0 &&
                  memcmp(again.material_of, s.material_of, sizeof(uint32_t) * s.triangle_count) ==
                      0,
              "%s: not deterministic", e->name);
        lanes_scene_free(&again);
    }
    if (strcmp(e->name, "hairball") == 0)
        CHECK(dt < 5.0, "hairball took %.2f s to generate", dt);
    lanes_scene_free(&s);
}

static const scene_expect builtins[] = {
    {"default", 2000, 6000, false},
    {"hairball", 2800000, 2960000, false},
    {"hairball-small", 50000, 100000, false},
    {"dragon", 70000, 110000, true},
    {"sponza-bunny", 120000, 150000, true},
    {"20-bunnies", 1300000, 1600000, true},
    {"20-bunnies-small", 50000, 100000, true},
};
#define N_BUILTINS (sizeof builtins / sizeof builtins[0])

static void test_builtins(bool with_meshes)
{
    for (size_t i = 0; i < N_BUILTINS; i++)
        if (builtins[i].needs_meshes == with_meshes)
            check_builtin(&builtins[i]);
    /* Every scene the library lists is tested here. */
    for (size_t i = 0; i < lanes_builtin_scene_count(); i++) {
        bool known = false;
        for (size_t j = 0; j < N_BUILTINS; j++)
            known = known || strcmp(builtins[j].name, lanes_builtin_scene_info(i)->name) == 0;
        CHECK(known, "built-in scene '%s' has no test", lanes_builtin_scene_info(i)->name);
    }
}

static void test_real_meshes(void)
{
    struct {
        const char *name;
        const char *file;
        size_t tris;
    } m[] = {{"bunny", "bunny00.off", 75408},
             {"dragon", "ChineseDragon-10kv.off", 19994},
             {"armadillo", "armadillo.off", 52000},
             {"elephant", "elephant.off", 5558}};
    for (size_t i = 0; i < sizeof m / sizeof m[0]; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", lanes_mesh_dir(), m[i].file);
        lanes_mesh mesh;
        lanes_error err;
        if (!CHECK(lanes_mesh_read(path, &mesh, &err) == LANES_OK, "%s", err.message)) continue;
        CHECK(mesh.triangle_count == m[i].tris, "%s: %zu triangles", path, mesh.triangle_count);
        printf("  %-24s %6zu triangles %6zu vertices\n", m[i].file, mesh.triangle_count,
               mesh.vertex_count);
        lanes_mesh_free(&mesh);
        /* Normalized as documented: on y = 0, centered, largest extent 1. */
        if (!CHECK(lanes_builtin_object(m[i].name, 0, &mesh, &err) == LANES_OK, "%s", err.message)) continue;
        float mn[3], mx[3];
        mesh_bounds(&mesh, mn, mx);
        float ext = fmaxf(mx[0] - mn[0], fmaxf(mx[1] - mn[1], mx[2] - mn[2]));
        CHECK(fabsf(mn[1]) < 1e-6f && fabsf(ext - 1.0f) < 1e-5f && fabsf(mn[0] + mx[0]) < 1e-5f &&
                  fabsf(mn[2] + mx[2]) < 1e-5f,
              "%s normalized", m[i].name);
        lanes_mesh_free(&mesh);
    }
    test_builtins(true);
}

/* ---- scene files ---- */

static void test_scene_files(void)
{
    lanes_scene s;
    lanes_error err;
    const char *room = data("scenes/ok/room.json");
    if (CHECK(lanes_scene_load(room, &s, &err) == LANES_OK, "%s", err.message)) {
        CHECK(strcmp(s.name, "test room") == 0, "name '%s'", s.name);
        /* plane 2 + box 12 + sphere(detail 2) 320 + quad 2 + tet 4 +
         * the visible area light 2 */
        CHECK(s.triangle_count == 342, "room: %zu triangles", s.triangle_count);
        CHECK(s.material_count == 6 && s.materials[5].kind == LANES_MAT_EMISSIVE &&
                  s.materials[5].name[0] == '@',
              "room: materials + the area light's");
        CHECK(s.point_light_count == 1 && s.area_light_count == 2, "room: lights");
        CHECK(s.camera.width == 320 && s.camera.height == 240 && s.camera.fov_y_degrees == 40.0f,
              "room: camera");
        long water = lanes_scene_find_material(&s, "water"),
             grey = lanes_scene_find_material(&s, "grey");
        CHECK(water == 3 && s.materials[3].kind == LANES_MAT_GLASS &&
                  fabsf(s.materials[3].ior - 1.33f) < 1e-6f && s.materials[3].roughness == 0.0f,
              "glass material");
        CHECK(grey == 1 && s.materials[1].color[2] == 0.5f, "grey from one number");
        CHECK(s.materials[2].kind == LANES_MAT_MIRROR && s.materials[2].color[0] == 1.0f,
              "mirror default color");
        /* The quad (rotated +90 about y, then moved to z = -1) lies in
         * x = 0, z in [-2, -1]. */
        size_t quad_tris = 0;
        for (size_t i = 0; i < s.triangle_count; i++) {
            if (s.material_of[i] != (uint32_t)water)
                continue;
            quad_tris++;
            for (int k = 0; k < 3; k++) {
                const float *v = s.verts + 9 * i + 3 * k;
                CHECK(fabsf(v[0]) < 1e-6f && v[2] >= -2.0f - 1e-6f && v[2] <= -1.0f + 1e-6f,
                      "quad vertex (%g %g %g)", v[0], v[1], v[2]);
            }
        }
        CHECK(quad_tris == 2, "quad triangles %zu", quad_tris);
        float mn[3], mx[3];
        lanes_scene_bounds(&s, mn, mx);
        CHECK(fabsf(mx[1] - 2.5f) < 1e-5f, "normalized tet on top: max y %g", mx[1]);
        CHECK(s.area_lights[1].emission[2] == 3.0f, "invisible area light kept");
        lanes_scene_free(&s);
    }
    if (CHECK(lanes_scene_load(data("scenes/ok/minimal.json"), &s, &err) == LANES_OK, "%s", err.message)) {
        CHECK(s.triangle_count == 12 && strcmp(s.name, "minimal") == 0, "minimal");
        /* No camera given: one framing the box from +z. */
        CHECK(s.camera.eye[2] > 1.0f && fabsf(s.camera.target[0]) < 1e-6f, "framed camera");
        lanes_scene_free(&s);
    }
    /* Every material type and texture, each key where it lands. */
    if (CHECK(lanes_scene_load(data("scenes/ok/materials.json"), &s, &err) == LANES_OK, "%s", err.message)) {
        const lanes_material *copper = &s.materials[lanes_scene_find_material(&s, "copper")],
                             *shiny = &s.materials[lanes_scene_find_material(&s, "shiny")],
                             *red = &s.materials[lanes_scene_find_material(&s, "red")],
                             *lamp = &s.materials[lanes_scene_find_material(&s, "lamp")],
                             *checker = &s.materials[lanes_scene_find_material(&s, "checker")],
                             *noise = &s.materials[lanes_scene_find_material(&s, "noise")],
                             *wood = &s.materials[lanes_scene_find_material(&s, "wood")];
        CHECK(copper->kind == LANES_MAT_CONDUCTOR && copper->roughness == 0.25f && copper->f0[1] == 0.64f &&
                  copper->color[1] == 0.64f,
              "conductor: roughness, f0 and the Whitted tint");
        CHECK(shiny->roughness == 0.3f && shiny->f0[2] == 0.9f, "conductor defaults");
        CHECK(red->kind == LANES_MAT_PLASTIC && red->roughness == 0.1f && red->color[0] == 0.7f, "plastic");
        CHECK(lamp->kind == LANES_MAT_DIFFUSE && lamp->emission[2] == 1.5f && lamp->color[0] == 0.5f,
              "emitting diffuse");
        CHECK(checker->texture == LANES_MAT_TEXTURE_CHECKER && checker->texture_scale == 0.25f &&
                  checker->texture_colors[0][2] == 0.1f && checker->texture_colors[1][2] == 0.7f &&
                  fabsf(checker->color[2] - 0.4f) < 1e-6f,
              "checker texture, its colors and their mean");
        CHECK(noise->kind == LANES_MAT_PLASTIC && noise->texture == LANES_MAT_TEXTURE_NOISE && noise->texture_scale == 1.0f,
              "textured plastic, default scale");
        CHECK(wood->texture == LANES_MAT_TEXTURE_WOOD, "wood");
        const lanes_material *frosted = &s.materials[lanes_scene_find_material(&s, "frosted")];
        CHECK(frosted->kind == LANES_MAT_GLASS && frosted->roughness == 0.4f && frosted->ior == 1.5f, "rough glass");
        lanes_scene_free(&s);
    }
    /* The library refuses what a file could not give: bad values, and a
     * material past the stream sort's 65536. */
    {
        lanes_scene t;
        lanes_scene_init(&t);
        lanes_material m;
        memset(&m, 0, sizeof m);
        m.kind = LANES_MAT_CONDUCTOR;
        m.roughness = 2.0f;
        snprintf(m.name, sizeof m.name, "rough");
        CHECK(lanes_scene_add_material(&t, &m, NULL, &err) == LANES_ERR_BAD_INPUT && strstr(err.message, "roughness"),
              "roughness 2 accepted: %s", err.message);
        m.roughness = 0.5f, m.f0[1] = 1.5f;
        CHECK(lanes_scene_add_material(&t, &m, NULL, &err) == LANES_ERR_BAD_INPUT && strstr(err.message, "f0"),
              "f0 1.5 accepted: %s", err.message);
        m.f0[1] = 0.5f, m.texture = LANES_MAT_TEXTURE_MARBLE, m.texture_scale = 1.0f;
        CHECK(lanes_scene_add_material(&t, &m, NULL, &err) == LANES_ERR_BAD_INPUT && strstr(err.message, "texture"),
              "a textured conductor accepted: %s", err.message);
        m.texture = LANES_MAT_TEXTURE_NONE;
        /* 65536 materials by hand (adding them one by one looks each name up) */
        t.materials = calloc(LANES_SCENE_MAX_MATERIALS, sizeof *t.materials);
        if (CHECK(t.materials != NULL, "out of memory")) {
            for (size_t i = 0; i < LANES_SCENE_MAX_MATERIALS; i++) snprintf(t.materials[i].name, 64, "m%zu", i);
            t.material_count = t.material_capacity = LANES_SCENE_MAX_MATERIALS;
            CHECK(lanes_scene_add_material(&t, &m, NULL, &err) == LANES_ERR_BAD_INPUT && strstr(err.message, "65536"),
                  "material 65537 accepted: %s", err.message);
        }
        lanes_scene_free(&t);
    }
    /* From memory, with a base directory for the mesh. */
    static const char text[] = "{\"materials\": {\"m\": {\"type\": \"diffuse\"}},"
                               " \"objects\": [{\"mesh\": \"quad.obj\", \"material\": \"m\"}]}";
    if (CHECK(lanes_scene_file_parse(text, sizeof text - 1, "inline", data("meshes/ok"), &s, &err) ==
                  LANES_OK,
              "%s", err.message)) {
        CHECK(s.triangle_count == 2, "inline scene");
        lanes_scene_free(&s);
    }

    /* Coordinates beyond LANES_SCENE_MAX_COORD are refused, naming the
     * object or the light; up to it they load. */
    static const struct {
        const char *what, *object, *light;
        bool loads;
    } far[] = {
        {"sphere at 1e38", "{\"builtin\": \"sphere\", \"name\": \"ball\", \"material\": \"m\", \"translate\": [1e38, 0, 0]}",
         "", false},
        {"sphere scaled to 1e19", "{\"builtin\": \"sphere\", \"name\": \"ball\", \"material\": \"m\", \"scale\": 1e19}", "",
         false},
        {"sphere at 1e17", "{\"builtin\": \"sphere\", \"name\": \"ball\", \"material\": \"m\", \"translate\": [1e17, 0, 0]}",
         "", true},
        {"point light at 1e30", "{\"builtin\": \"box\", \"name\": \"ball\", \"material\": \"m\"}",
         ", \"lights\": [{\"type\": \"point\", \"position\": [0, 1e30, 0], \"intensity\": 1}]", false},
    };
    for (size_t i = 0; i < sizeof far / sizeof far[0]; i++) {
        char scene_text[512];
        snprintf(scene_text, sizeof scene_text, "{\"materials\": {\"m\": {\"type\": \"diffuse\"}}, \"objects\": [%s]%s}",
                 far[i].object, far[i].light);
        lanes_status st = lanes_scene_file_parse(scene_text, strlen(scene_text), "far.json", NULL, &s, &err);
        if (far[i].loads) {
            if (CHECK(st == LANES_OK, "%s: %s", far[i].what, err.message)) lanes_scene_free(&s);
        } else {
            bool named = strstr(err.message, far[i].light[0] ? "point light" : "ball") != NULL;
            CHECK(st == LANES_ERR_BAD_INPUT && named && strstr(err.message, "1e+18") && strstr(err.message, "far.json"),
                  "%s: %s", far[i].what, st == LANES_OK ? "loaded" : err.message);
            if (st == LANES_OK) lanes_scene_free(&s);
        }
    }
}

/* The geometric normal at every scale: edges scaled by 2^k give the same
 * unit normal, bit for bit, and a finite one (normalizing the cross product
 * directly overflows past |k| of about 31). */
static void test_unit_normal(void)
{
    const vec3 e1 = v3(0.3f, -1.7f, 0.25f), e2 = v3(-0.9f, 0.4f, 1.1f);
    float area1;
    const vec3 n1 = v3_unit_normal_area(e1, e2, &area1);
    CHECK(fabsf(v3_dot(n1, n1) - 1.0f) < 1e-6f && area1 > 0.0f, "unit normal of unit edges");
    for (int k = -120; k <= 120; k += 4) {
        float s = ldexpf(1.0f, k), area;
        vec3 n = v3_unit_normal_area(v3_scale(e1, s), v3_scale(e2, s), &area);
        CHECK(n.x == n1.x && n.y == n1.y && n.z == n1.z, "edges scaled by 2^%d: normal (%g, %g, %g), want (%g, %g, %g)",
              k, n.x, n.y, n.z, n1.x, n1.y, n1.z);
        /* the area scales by 2^2k while it stays a normal float */
        if (2 * k > -126 && 2 * k < 127)
            CHECK(area == ldexpf(area1, 2 * k), "edges scaled by 2^%d: area %g, want %g", k, area, ldexpf(area1, 2 * k));
    }
    float area;
    vec3 z = v3_unit_normal_area(e1, v3_scale(e1, 2.0f), &area);
    CHECK(z.x == 0.0f && z.y == 0.0f && z.z == 0.0f && area == 0.0f, "parallel edges: no normal");
}

/* ---- lanes_scene_load ---- */

static void test_load(void)
{
    lanes_scene s;
    lanes_error err;
    if (CHECK(lanes_scene_load(NULL, &s, &err) == LANES_OK, "NULL: %s", err.message)) {
        CHECK(strcmp(s.name, "default") == 0, "NULL gives the default scene");
        lanes_scene_free(&s);
    }
    if (CHECK(lanes_scene_load("", &s, &err) == LANES_OK, "\"\": %s", err.message)) {
        CHECK(strcmp(s.name, "default") == 0, "\"\" gives the default scene");
        lanes_scene_free(&s);
    }
    CHECK(lanes_scene_load("sponza", &s, &err) != LANES_OK && strstr(err.message, "sponza") &&
              strstr(err.message, "valid") && strstr(err.message, "sponza-bunny") &&
              strstr(err.message, "hairball-small"),
          "unknown name lists the valid ones: %s", err.message);
    CHECK(s.triangle_count == 0 && s.verts == NULL, "failed load leaves an empty scene");
    CHECK(lanes_scene_load("no/such/mesh.obj", &s, &err) != LANES_OK &&
              strstr(err.message, "no/such/mesh.obj: no such file"),
          "missing mesh: %s", err.message);
    CHECK(lanes_scene_load("missing-scene.json", &s, &err) != LANES_OK &&
              strstr(err.message, "missing-scene.json: no such file"),
          "missing scene file: %s", err.message);
    if (CHECK(lanes_scene_load(data("meshes/ok/tet.ply"), &s, &err) == LANES_OK, "mesh: %s", err.message)) {
        CHECK(s.triangle_count == 4 && s.point_light_count == 1 && s.material_count == 1 &&
                  lanes_scene_validate(&s, &err) == LANES_OK,
              "a mesh file becomes a lit scene");
        lanes_scene_free(&s);
    }
    /* The meshes are looked up where LANES_MESH_DIR says, and their
     * absence says how to fetch them. */
    const char *old = getenv("LANES_MESH_DIR");
    char saved[4096] = "";
    if (old)
        snprintf(saved, sizeof saved, "%s", old);
    setenv("LANES_MESH_DIR", "/nonexistent/lanes-meshes", 1);
    CHECK(lanes_scene_load("dragon", &s, &err) != LANES_OK && strstr(err.message, "fetch_meshes.sh") &&
              strstr(err.message, "/nonexistent/lanes-meshes/ChineseDragon-10kv.off"),
          "missing meshes: %s", err.message);
    if (old)
        setenv("LANES_MESH_DIR", saved, 1);
    else
        unsetenv("LANES_MESH_DIR");
}

/* ---- the malformed corpus ---- */

typedef struct bad_case {
    const char *path; /* relative to DATA, or "!" + name in SCRATCH */
    const char *expect[4];
} bad_case;

static const bad_case bad_meshes[] = {
    {"meshes/bad/nan_vertex.obj", {"line 3", "not a finite"}},
    {"meshes/bad/inf_vertex.off", {"line 5", "not a finite"}},
    {"meshes/bad/overflow_vertex.ply", {"line 12", "not a finite"}},
    {"meshes/bad/index_oob.obj", {"line 5", "out of range"}},
    {"meshes/bad/index_zero.obj", {"line 4", "index 0"}},
    {"meshes/bad/index_negative.obj", {"line 4", "-4"}},
    {"meshes/bad/index_plus.obj", {"line 5", "'+4'", "several indices"}},
    {"meshes/bad/index_leading_zero.obj", {"line 6", "'004'", "leading zero"}},
    {"meshes/bad/index_oob.off", {"line 7", "out of range"}},
    {"meshes/bad/index_oob.ply", {"line 14", "out of range"}},
    {"meshes/bad/truncated_vertices.off", {"line 5"}},
    {"meshes/bad/truncated_faces.off", {"line 6", "truncated"}},
    {"meshes/bad/truncated_face.off", {"line 6", "2 of its 3"}},
    {"meshes/bad/truncated.ply", {"line 11", "truncated"}},
    {"meshes/bad/truncated_header.ply", {"line 4", "end_header"}},
    {"meshes/bad/truncated.stl", {"line 5", "truncated"}},
    {"meshes/bad/four_vertices.stl", {"line 8", "4 vertices"}},
    {"meshes/bad/continued_at_end.obj", {"line 4", "line continuation"}},
    {"meshes/bad/huge_counts.off", {"line 3", "truncated"}},
    {"meshes/bad/absurd_count.off", {"line 2", "out of range"}},
    {"meshes/bad/huge_counts.ply", {"line 10", "truncated"}},
    {"meshes/bad/bad_number.obj", {"line 2", "bad number 'zero'"}},
    {"meshes/bad/hex_number.off", {"line 4", "bad number"}},
    {"meshes/bad/short_vertex.obj", {"line 2", "fewer than 3"}},
    {"meshes/bad/empty.obj", {"empty file"}},
    {"meshes/bad/points_only.obj", {"no triangles"}},
    {"meshes/bad/point_cloud.ply", {"line 7", "no faces"}},
    {"meshes/bad/not_off.off", {"line 2", "not an OFF file"}},
    {"meshes/bad/bad_header.ply", {"line 7", "proprety"}},
    {"meshes/bad/duplicate_element.ply", {"line 9", "element 'face' declared twice"}},
    {"meshes/bad/garbage.dat", {"cannot import"}},
    /* formats Assimp reads but lanes does not check: refused by extension */
    {"meshes/bad/huge_count.x", {"'.x' is not one of them", ".obj, .ply, .off, .stl, .gltf and .glb"}},
    {"meshes/bad/huge_count.nff", {"'.nff' is not one of them"}},
    {"meshes/bad/index_oob.ac", {"'.ac' is not one of them"}},
    {"meshes/bad/tiny.3ds", {"'.3ds' is not one of them"}},
    {"meshes/bad/index_oob.gltf", {"Assimp kept 1"}},
    {"meshes/bad/nan.gltf", {"not finite"}},
    {"meshes/bad/huge_accessor.gltf", {"out of range"}},
    {"meshes/bad/cycle.gltf", {"recursive"}},
    {"meshes/bad/missing_buffer.gltf", {"missing.bin"}},
    {"meshes/bad/syntax.gltf", {"line 3", "syntax"}},
    {"meshes/bad/no_such_file.obj", {"no such file"}},
    {"meshes/bad", {"is a directory"}},
    {"!trunc_bin.stl", {"truncated"}},
    {"!wrap_bin.stl", {"far more"}},
    {"!nan_bin.stl", {"byte", "not finite"}},
    {"!trunc_bin.ply", {"byte", "truncated"}},
    {"!oob_bin.ply", {"byte", "out of range"}},
    {"!trunc.glb", {"GLB header", "truncated"}},
};

static const bad_case bad_scenes[] = {
    {"scenes/bad/syntax.json", {"line 4", "syntax error"}},
    {"scenes/bad/truncated.json", {"line 3", "end of file"}},
    {"scenes/bad/trailing.json", {"line 2", "syntax error"}},
    {"scenes/bad/unknown_key.json", {"line 7", "materials.red.colour", "unknown key 'colour'"}},
    {"scenes/bad/unknown_top_key.json", {"line 4", "unknown key 'light'"}},
    {"scenes/bad/wrong_type.json", {"line 5", "camera.fov", "expected a number"}},
    {"scenes/bad/wrong_length.json", {"line 5", "objects[0].translate", "3 numbers"}},
    {"scenes/bad/undefined_material.json", {"line 7", "objects[1].material", "'blue'"}},
    {"scenes/bad/missing_material_key.json", {"line 4", "missing required key 'material'"}},
    {"scenes/bad/mesh_and_builtin.json", {"line 4", "exactly one"}},
    {"scenes/bad/missing_mesh.json", {"line 4", "no_such_mesh.obj", "no such file"}},
    {"scenes/bad/broken_mesh.json", {"line 4", "nan_vertex.obj: line 3", "not a finite"}},
    {"scenes/bad/duplicate_key.json", {"line 2", "duplicate key 'color'"}},
    {"scenes/bad/duplicate_material.json", {"line 3", "defined twice"}},
    {"scenes/bad/flat_area_light.json", {"line 6", "lights[1]", "no area"}},
    {"scenes/bad/negative_color.json", {"line 3", ">= 0"}},
    {"scenes/bad/unknown_material_type.json", {"line 3", "'metal'"}},
    {"scenes/bad/unknown_accuracy.json", {"line 3", "'exact'", "fast, default, robust"}},
    {"scenes/bad/ior_on_diffuse.json", {"line 3", "unknown key 'ior'"}},
    {"scenes/bad/unknown_builtin.json", {"line 4", "'teapot'", "valid"}},
    {"scenes/bad/fractional_detail.json", {"line 4", "integer"}},
    {"scenes/bad/huge_number.json", {"line 2", "out of range"}},
    {"scenes/bad/camera_up_parallel.json", {"line 2", "parallel"}},
    {"scenes/bad/huge_camera.json", {"line 5", "camera.width", "16384"}},
    {"scenes/bad/nul_key.json", {"line 2", "\\u0000", "NUL"}},
    {"scenes/bad/no_objects.json", {"line 3", "no objects"}},
    {"scenes/bad/not_object.json", {"line 1", "top level"}},
    {"scenes/bad/empty.json", {"empty file"}},
    {"scenes/bad/blank.json", {"empty file"}},
    {"scenes/bad/zero_scale.json", {"line 3", "scale"}},
    {"scenes/bad/reserved_name.json", {"line 2", "reserved"}},
    {"scenes/bad/roughness_above_one.json", {"line 3", "materials.m.roughness", "out of range [0, 1]"}},
    {"scenes/bad/albedo_above_one.json", {"line 3", "materials.m.color", "reflectance lies in [0, 1], found 1.2"}},
    {"scenes/bad/ior_zero.json", {"line 3", "materials.m.ior", "out of range"}},
    {"scenes/bad/unknown_texture.json", {"line 3", "texture.type", "'bricks' (valid: checker, noise, marble, wood)"}},
    {"scenes/bad/color_and_texture.json", {"line 3", "materials.m", "not both"}},
    {"scenes/bad/f0_on_plastic.json", {"line 3", "unknown key 'f0' in a plastic material"}},
    {"scenes/bad/texture_one_color.json", {"line 3", "texture.colors", "two colors"}},
    {"scenes/bad/texture_bright.json", {"line 3", "texture.colors[1]", "reflectance"}},
    {"scenes/bad/negative_emission.json", {"line 3", "materials.m.emission", ">= 0"}},
    {"scenes/bad/rough_glass_ior_one.json", {"line 3", "materials.m", "within 1e-4 of 1"}},
    {"scenes/bad/no_such_scene.json", {"no such file"}},
    {"!deep.json", {"syntax error"}},
};

static void write_bad_generated(void)
{
    write_stl_bin(scratch("trunc_bin.stl"), 4, 3, false);
    write_stl_bin(scratch("nan_bin.stl"), 4, 4, true);
    /* 84 + 50 * 2147483649 wraps to the size of a 1-triangle file in 32
     * bits. */
    write_stl_bin(scratch("wrap_bin.stl"), 2147483649u, 1, false);
    write_ply_bin(scratch("trunc_bin.ply"), false, 0, 3);
    write_ply_bin(scratch("oob_bin.ply"), true, 9, 4);
    write_glb(scratch("trunc.glb"), 30);
    /* Nesting past cJSON's limit (1000) must be an error, not a stack
     * overflow. */
    static char deep[4002];
    for (int i = 0; i < 2000; i++) {
        deep[i] = '[';
        deep[2000 + i] = ']';
    }
    deep[4000] = '\n';
    write_file(scratch("deep.json"), deep, 4001);
}

static const char *case_path(const bad_case *c)
{
    return c->path[0] == '!' ? scratch(c->path + 1) : data(c->path);
}

static void test_corpus(void)
{
    write_bad_generated();
    for (size_t i = 0; i < sizeof bad_meshes / sizeof bad_meshes[0]; i++) {
        const char *path = case_path(&bad_meshes[i]);
        lanes_mesh m;
        lanes_error err;
        memset(&err, 0, sizeof err);
        if (CHECK(lanes_mesh_read(path, &m, &err) != LANES_OK, "%s: accepted", path)) {
            check_message(path, path, err.message, bad_meshes[i].expect);
            CHECK(m.positions == NULL && m.indices == NULL && m.triangle_count == 0,
                  "%s: failed read leaves an empty mesh", path);
        } else {
            lanes_mesh_free(&m);
        }
        /* The same file as a scene spec goes through the same checks. */
        lanes_scene s;
        if (!CHECK(lanes_scene_load(path, &s, &err) != LANES_OK, "%s: loaded as a scene", path))
            lanes_scene_free(&s);
    }
    for (size_t i = 0; i < sizeof bad_scenes / sizeof bad_scenes[0]; i++) {
        const char *path = case_path(&bad_scenes[i]);
        lanes_scene s;
        lanes_error err;
        memset(&err, 0, sizeof err);
        if (CHECK(lanes_scene_load(path, &s, &err) != LANES_OK, "%s: accepted", path)) {
            check_message(path, path, err.message, bad_scenes[i].expect);
            CHECK(s.triangle_count == 0 && s.verts == NULL && s.materials == NULL,
                  "%s: failed load leaves an empty scene", path);
        } else {
            lanes_scene_free(&s);
        }
    }
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: test_scenes DATA_DIR SCRATCH_DIR [--meshes | --corpus]\n");
        return 2;
    }
    g_data = argv[1];
    g_scratch = argv[2];
    const char *mode = argc > 3 ? argv[3] : "";
    if (strcmp(mode, "--meshes") == 0) {
        if (!lanes_builtin_meshes_available()) {
            printf("skipped: the CGAL meshes are not in %s (run cmake/fetch_meshes.sh)\n",
                   lanes_mesh_dir());
            return 77;
        }
        test_real_meshes();
    } else if (strcmp(mode, "--corpus") == 0) {
        test_corpus();
    } else {
        test_container();
        test_memory_limit();
        test_load_ceilings();
        test_mesh_formats();
        test_generators();
        test_scene_files();
        test_unit_normal();
        test_load();
        test_corpus();
        test_builtins(false);
    }
    char name[64];
    snprintf(name, sizeof name, "test_scenes %s", mode);
    return harness_summary(name);
}
