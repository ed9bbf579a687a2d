/* Mesh files: the streaming checkers of mesh_check.h, then Assimp, then
 * checks on what Assimp returns. See mesh_import.h for why all three are
 * needed.
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L /* stat, for "is a directory" before Assimp sees it */

#include "build/mesh_import.h"

#include "build/mesh_check.h"

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <sys/stat.h>

#define MAX_NODE_DEPTH 256 /* Assimp node hierarchy */

/* ---- Assimp ---- */

/* Every file Assimp opens goes through these callbacks: the mesh, and the
 * files it names (an OBJ's mtllib, a glTF's buffers and images). Only
 * regular files open. Assimp's own file system opens whatever fopen opens,
 * directories included: "mtllib /" made it open the OBJ's directory, fail
 * to read it and leak the stream (found by fuzz_mesh_obj), and a FIFO would
 * block it. Read-only: Assimp never needs to write here. */
typedef struct {
    FILE *f;
    /* An ASCII STL: the checker takes its keywords in any case ("SOLID",
     * "FACET NORMAL", "vertEx"), Assimp's STL reader in lower case only (it
     * takes "SOLID" for binary, and leaked on "vertEx", found by
     * fuzz_mesh_stl), so Assimp reads it lower-cased (the numbers read the
     * same; only the solid's name changes). */
    bool lower;
} io_state;

static FILE *io_file(struct aiFile *a)
{
    return ((io_state *)(void *)a->UserData)->f;
}

static size_t io_read(struct aiFile *a, char *buf, size_t size, size_t count)
{
    if (!size || !count) return 0;
    size_t got = fread(buf, size, count, io_file(a));
    if (((io_state *)(void *)a->UserData)->lower)
        for (size_t i = 0; i < got * size; i++)
            if (buf[i] >= 'A' && buf[i] <= 'Z') buf[i] = (char)(buf[i] + ('a' - 'A'));
    return got;
}

/* An ASCII STL: by extension, by a first word "solid" in any case, and by
 * a size that is not a binary STL's. */
static bool stl_needs_lowering(const char *path, FILE *f, long long size)
{
    if (!mesh_ext_is(path, "stl")) return false;
    unsigned char head[84];
    size_t n = fread(head, 1, sizeof head, f);
    rewind(f);
    if (!mesh_starts_solid(head, n)) return false;
    if (n == sizeof head) {
        unsigned long long count = mesh_stl_declared_count(head);
        if ((unsigned long long)size == 84ull + 50ull * count) return false;
    }
    return true;
}

static size_t io_write(struct aiFile *a, const char *buf, size_t size, size_t count)
{
    (void)a;
    (void)buf;
    (void)size;
    (void)count;
    return 0;
}

static size_t io_tell(struct aiFile *a)
{
    long p = ftell(io_file(a));
    return p < 0 ? 0 : (size_t)p;
}

static size_t io_size(struct aiFile *a)
{
    struct stat st;
    return fstat(fileno(io_file(a)), &st) == 0 ? (size_t)st.st_size : 0;
}

static enum aiReturn io_seek(struct aiFile *a, size_t offset, enum aiOrigin origin)
{
    int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    return fseek(io_file(a), (long)offset, whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
}

static void io_flush(struct aiFile *a)
{
    (void)a;
}

/* io->UserData, when set, is the one path Assimp may open: an OBJ file's
 * material libraries ("mtllib", any path, the file itself included) are
 * not read, since lanes assigns its own materials. Other formats may need
 * files beside them (a glTF file's buffers). */
static struct aiFile *io_open(struct aiFileIO *io, const char *path, const char *mode)
{
    struct stat st;
    const char *only = (const char *)io->UserData;
    if ((only && strcmp(path, only) != 0) || strpbrk(mode, "wa+") || stat(path, &st) != 0 ||
        !S_ISREG(st.st_mode))
        return NULL;
    struct aiFile *a = calloc(1, sizeof *a);
    io_state *state = calloc(1, sizeof *state);
    FILE *f = a && state ? fopen(path, "rb") : NULL;
    if (!f) {
        free(a);
        free(state);
        return NULL;
    }
    state->f = f;
    state->lower = stl_needs_lowering(path, f, (long long)st.st_size);
    a->ReadProc = io_read;
    a->WriteProc = io_write;
    a->TellProc = io_tell;
    a->FileSizeProc = io_size;
    a->SeekProc = io_seek;
    a->FlushProc = io_flush;
    a->UserData = (aiUserData)(void *)state;
    return a;
}

static void io_close(struct aiFileIO *io, struct aiFile *a)
{
    (void)io;
    if (a) {
        fclose(io_file(a));
        free((void *)a->UserData);
        free(a);
    }
}

/* Assimp's own messages rarely name the file; some do, most do not. */
static lanes_status assimp_error(const char *path, const char *what, lanes_error *err)
{
    const char *msg = aiGetErrorString();
    if (!msg || !*msg)
        msg = "unknown error";
    return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %s: %s", path, what, msg);
}

static const char *mesh_name(const struct aiMesh *m)
{
    return m->mName.length > 0 ? m->mName.data : "";
}

/* The raw import, before any post-processing runs on it: post-processing
 * steps assume a well-formed structure (Triangulate would follow a null
 * index array), so this is where a half-read file must be caught. */
static lanes_status check_raw(const char *path, const struct aiScene *sc, lanes_error *err)
{
    if (sc->mNumMeshes > 0 && !sc->mMeshes) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: Assimp returned no mesh array", path);
    }
    for (unsigned m = 0; m < sc->mNumMeshes; m++) {
        const struct aiMesh *me = sc->mMeshes[m];
        if (!me || (me->mNumVertices > 0 && !me->mVertices) || (me->mNumFaces > 0 && !me->mFaces)) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: mesh %u is incomplete (truncated file?)",
                                   path, m);
        }
        for (unsigned v = 0; v < me->mNumVertices; v++) {
            const struct aiVector3D *p = &me->mVertices[v];
            if (!isfinite(p->x) || !isfinite(p->y) || !isfinite(p->z)) {
                return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: mesh %u '%s': vertex %u is not finite",
                                       path, m, mesh_name(me), v);
            }
        }
        for (unsigned f = 0; f < me->mNumFaces; f++) {
            const struct aiFace *fa = &me->mFaces[f];
            if (fa->mNumIndices == 0 || !fa->mIndices) {
                return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                       "%s: mesh %u '%s': face %u has no vertices (truncated "
                                       "file?)",
                                       path, m, mesh_name(me), f);
            }
            for (unsigned k = 0; k < fa->mNumIndices; k++) {
                if (fa->mIndices[k] >= me->mNumVertices) {
                    return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                           "%s: mesh %u '%s': face %u refers to vertex %u of %u", path, m,
                                           mesh_name(me), f, fa->mIndices[k], me->mNumVertices);
                }
            }
        }
    }
    return LANES_OK;
}

typedef struct collect {
    const char *path;
    const struct aiScene *sc;
    lanes_mesh *out;
    bool fill; /* false: count only */
    unsigned long long tris, verts;
    lanes_error *err;
} collect;

static void to_xform(const struct aiMatrix4x4 *a, lanes_xform *x)
{
    const double r[3][4] = {
        {a->a1, a->a2, a->a3, a->a4}, {a->b1, a->b2, a->b3, a->b4}, {a->c1, a->c2, a->c3, a->c4}};
    memcpy(x->m, r, sizeof r);
}

static bool walk(collect *c, const struct aiNode *node, const lanes_xform *parent, int depth)
{
    if (depth > MAX_NODE_DEPTH) {
        lanes_error_set(c->err, LANES_ERR_BAD_INPUT, "%s: node hierarchy deeper than %d (a cycle?)", c->path,
                        MAX_NODE_DEPTH);
        return false;
    }
    lanes_xform local, x;
    to_xform(&node->mTransformation, &local);
    lanes_xform_mul(&x, parent, &local);
    for (unsigned i = 0; i < node->mNumMeshes; i++) {
        unsigned mi = node->mMeshes[i];
        if (mi >= c->sc->mNumMeshes) {
            lanes_error_set(c->err, LANES_ERR_BAD_INPUT, "%s: node '%s' refers to mesh %u of %u", c->path,
                            node->mName.data, mi, c->sc->mNumMeshes);
            return false;
        }
        const struct aiMesh *me = c->sc->mMeshes[mi];
        unsigned long long ntri = 0;
        for (unsigned f = 0; f < me->mNumFaces; f++)
            ntri += me->mFaces[f].mNumIndices == 3;
        if (ntri == 0)
            continue;
        if (!c->fill) {
            c->tris += ntri;
            c->verts += me->mNumVertices;
            if (c->tris > LANES_SCENE_MAX_TRIANGLES || c->verts > MAX_VERTICES) {
                lanes_error_set(c->err, LANES_ERR_BAD_INPUT, "%s: more than %zu triangles or %llu vertices",
                                c->path, LANES_SCENE_MAX_TRIANGLES, MAX_VERTICES);
                return false;
            }
            continue;
        }
        uint32_t base = (uint32_t)c->verts;
        for (unsigned v = 0; v < me->mNumVertices; v++) {
            const struct aiVector3D *p = &me->mVertices[v];
            float in[3] = {p->x, p->y, p->z};
            float *o = c->out->positions + 3 * (c->verts + v);
            lanes_xform_apply(&x, in, o);
            if (!isfinite(o[0]) || !isfinite(o[1]) || !isfinite(o[2])) {
                lanes_error_set(c->err, LANES_ERR_BAD_INPUT,
                                "%s: mesh %u '%s': vertex %u is not finite after the "
                                "node transforms",
                                c->path, mi, mesh_name(me), v);
                return false;
            }
        }
        uint32_t *idx = c->out->indices + 3 * c->tris;
        for (unsigned f = 0; f < me->mNumFaces; f++) {
            const struct aiFace *fa = &me->mFaces[f];
            if (fa->mNumIndices != 3)
                continue; /* points and lines */
            for (int k = 0; k < 3; k++) {
                /* Checked again: post-processing rewrote the indices. */
                if (!fa->mIndices || fa->mIndices[k] >= me->mNumVertices) {
                    lanes_error_set(c->err, LANES_ERR_BAD_INPUT,
                                    "%s: mesh %u: face %u has a bad index after "
                                    "triangulation",
                                    c->path, mi, f);
                    return false;
                }
                *idx++ = base + fa->mIndices[k];
            }
        }
        c->tris += ntri;
        c->verts += me->mNumVertices;
    }
    if (node->mNumChildren > 0 && !node->mChildren) {
        lanes_error_set(c->err, LANES_ERR_BAD_INPUT, "%s: node '%s' has no child array", c->path,
                        node->mName.data);
        return false;
    }
    for (unsigned i = 0; i < node->mNumChildren; i++) {
        if (!node->mChildren[i] || !walk(c, node->mChildren[i], &x, depth + 1))
            return false;
    }
    return true;
}

/* Joins vertices at exactly the same position, across meshes and node
 * instances too. Assimp's JoinIdenticalVertices also compares normals and
 * texture coordinates, so an STL (one normal per facet) would keep three
 * vertices per triangle and lose all connectivity. */
static bool weld(lanes_mesh *m)
{
    size_t n = m->vertex_count, size = 16;
    while (size < 2 * n)
        size *= 2;
    uint32_t *slot = calloc(size, sizeof *slot); /* vertex index + 1; 0 = empty */
    uint32_t *remap = malloc((n ? n : 1) * sizeof *remap);
    if (!slot || !remap) {
        free(slot);
        free(remap);
        return false;
    }
    size_t kept = 0;
    float *p = m->positions;
    for (size_t v = 0; v < n; v++) {
        float q[3];
        uint32_t bits[3];
        for (int a = 0; a < 3; a++)
            q[a] = p[3 * v + a] + 0.0f; /* -0 and +0 are one position */
        memcpy(bits, q, sizeof bits);
        uint64_t h = (bits[0] * 0x9e3779b97f4a7c15ull) ^ (bits[1] * 0xc2b2ae3d27d4eb4full) ^
                     (bits[2] * 0x165667b19e3779f9ull);
        size_t i = (size_t)(h ^ (h >> 29)) & (size - 1);
        for (;;) {
            if (slot[i] == 0) {
                slot[i] = (uint32_t)kept + 1;
                memcpy(p + 3 * kept, q, sizeof q);
                remap[v] = (uint32_t)kept++;
                break;
            }
            const float *o = p + 3 * (slot[i] - 1);
            if (o[0] == q[0] && o[1] == q[1] && o[2] == q[2]) {
                remap[v] = slot[i] - 1;
                break;
            }
            i = (i + 1) & (size - 1);
        }
    }
    for (size_t k = 0; k < 3 * m->triangle_count; k++)
        m->indices[k] = remap[m->indices[k]];
    m->vertex_count = kept;
    free(slot);
    free(remap);
    return true;
}

/* Only the formats checked before import are passed to Assimp: each has a
 * streaming checker (mesh_precheck.c) or, for glTF, a check of its declared
 * counts, and a fuzz target (tests/fuzz/). Assimp reads many more, but
 * trusts their headers: a .x or .nff declaring 2e9 vertices ran to 11.5 GB
 * past LANES_MEMORY_LIMIT, and .3ds and .ac files with out-of-range
 * indices were repaired and rendered without a word. For an extension no
 * importer claims, Assimp would also try every importer on the content
 * (glTF text in a .dat file reached the glTF importer without the glTF
 * checks, found by fuzzing). */
static const char *const accepted_extensions[] = {"obj", "ply", "off", "stl", "gltf", "glb"};

static lanes_status known_extension(const char *path, lanes_error *err)
{
    for (size_t i = 0; i < sizeof accepted_extensions / sizeof accepted_extensions[0]; i++)
        if (mesh_ext_is(path, accepted_extensions[i])) return LANES_OK;
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    bool has_ext = dot && dot != base && dot[1];
    return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                           "%s: cannot import: %s%s%s; lanes reads mesh files by their extension: .obj, "
                           ".ply, .off, .stl, .gltf and .glb (the formats it checks before import)",
                           path, has_ext ? "file extension '" : "no file extension", has_ext ? dot : "",
                           has_ext ? "' is not one of them" : "");
}

lanes_status lanes_mesh_read(const char *path, lanes_mesh *out, lanes_error *err)
{
    lanes_status status;
    /* the steps below (precheck, Assimp's walk) report through err */
    lanes_error local;
    if (!err) err = &local;
    memset(out, 0, sizeof *out);
    if ((status = lanes_mesh_precheck(path, err)) != LANES_OK ||
        (status = known_extension(path, err)) != LANES_OK)
        return status;
    unsigned long long expected = 0;
    int gl = mesh_gltf_expected(path, &expected, err);
    if (gl < 0) return err->status;

    struct aiPropertyStore *props = aiCreatePropertyStore();
    if (!props) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    /* Skeleton-only meshes are bone visualizations, not geometry. */
    aiSetImportPropertyInteger(props, AI_CONFIG_IMPORT_NO_SKELETON_MESHES, 1);
    struct aiFileIO io = {io_open, io_close, mesh_ext_is(path, "obj") ? (aiUserData)path : NULL};
    const struct aiScene *sc = aiImportFileExWithProperties(path, 0, &io, props);
    aiReleasePropertyStore(props);
    if (!sc) {
        return assimp_error(path, "cannot import", err);
    }
    bool ok = false;
    if (check_raw(path, sc, err) != LANES_OK) goto done;
    unsigned long long got = 0;
    for (unsigned m = 0; m < sc->mNumMeshes; m++)
        for (unsigned f = 0; f < sc->mMeshes[m]->mNumFaces; f++)
            got += sc->mMeshes[m]->mFaces[f].mNumIndices == 3;
    if (gl > 0 && got < expected) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT,
                        "%s: the primitives describe %llu triangles but Assimp kept %llu "
                        "(out-of-range vertex indices?)",
                        path, expected, got);
        goto done;
    }
    /* ValidateDataStructure is left out on purpose: check_raw covers what
     * we rely on, and the validator rejects files that are fine for us
     * (an OBJ "f 1 2" makes it fail on its own primitive-type flags). */
    sc = aiApplyPostProcessing(sc, aiProcess_Triangulate);
    if (!sc) {
        return assimp_error(path, "post-processing failed", err);
    }
    if (!sc->mRootNode) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: the file has no node hierarchy", path);
        goto done;
    }
    collect c = {path, sc, out, false, 0, 0, err};
    lanes_xform id;
    lanes_xform_identity(&id);
    if (!walk(&c, sc->mRootNode, &id, 0))
        goto done;
    if (c.tris == 0) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: no triangles (only points, lines or empty meshes)",
                        path);
        goto done;
    }
    out->positions = malloc((size_t)c.verts * 3 * sizeof(float));
    out->indices = malloc((size_t)c.tris * 3 * sizeof(uint32_t));
    if (!out->positions || !out->indices) {
        lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory for %llu triangles", path, c.tris);
        goto done;
    }
    out->vertex_count = (size_t)c.verts;
    out->triangle_count = (size_t)c.tris;
    c.fill = true;
    c.tris = c.verts = 0;
    if (!walk(&c, sc->mRootNode, &id, 0))
        goto done;
    if (!weld(out)) {
        lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory joining vertices", path);
        goto done;
    }
    ok = true;
done:
    aiReleaseImport(sc);
    if (!ok)
        lanes_mesh_free(out);
    return ok ? LANES_OK : err->status;
}

lanes_status lanes_mesh_import(lanes_scene *scene, const char *path, const lanes_xform *xf, uint32_t material,
                               lanes_error *err)
{
    lanes_status status;
    lanes_mesh m;
    if ((status = lanes_mesh_read(path, &m, err)) != LANES_OK) return status;
    status = lanes_scene_add_mesh(scene, &m, xf, material, path, err);
    lanes_mesh_free(&m);
    return status;
}
