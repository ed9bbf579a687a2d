/* glTF and GLB: the triangle counts the primitives declare, through cJSON,
 * to hold Assimp's import against (mesh_check.h).
 *
 * Compiled for the x86-64 baseline. */

#include "build/mesh_check.h"
#include <cjson/cJSON.h>

#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#define MAX_GLTF_JSON (64u << 20)

/* A glTF integer as Assimp's reader takes it: 2.5 or 1e0 are not one
 * (rapidjson keeps them as doubles, and Assimp then ignores the member,
 * where cJSON's valueint would silently truncate). -1: not an integer in
 * [0, max]. */
static long long gltf_int(const cJSON *v, double max)
{
    if (!cJSON_IsNumber(v) || !(v->valuedouble >= 0 && v->valuedouble <= max) ||
        v->valuedouble != floor(v->valuedouble))
        return -1;
    return (long long)v->valuedouble;
}

static long long accessor_count(const cJSON *accessors, const cJSON *index)
{
    long long i = gltf_int(index, INT_MAX);
    const cJSON *a = i >= 0 ? cJSON_GetArrayItem(accessors, (int)i) : NULL;
    return a ? gltf_int(cJSON_GetObjectItemCaseSensitive(a, "count"), 1e15) : -1;
}

/* Data URIs that Assimp 5.2 misreads: it leaks its buffers when the data
 * holds a character outside base64, and it keeps the offsets of the
 * parts of a URI in a signed char, so a media type of more than about 120
 * characters makes it read before the string (found by fuzz_mesh_gltf).
 * Both are refused here, for buffers and images alike. */
static lanes_status check_data_uris(const char *path, const cJSON *root, const char *array, lanes_error *err)
{
    const cJSON *it;
    int i = 0;
    cJSON_ArrayForEach(it, cJSON_GetObjectItemCaseSensitive(root, array))
    {
        const cJSON *uri = cJSON_GetObjectItemCaseSensitive(it, "uri");
        const char *u = cJSON_IsString(uri) ? uri->valuestring : NULL;
        if (u && strncmp(u, "data:", 5) == 0) {
            const char *comma = strchr(u, ',');
            if (!comma || comma - u > 100) {
                return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %s[%d].uri: malformed data URI (%s)",
                                       path, array, i,
                                       comma ? "header longer than 100 characters" : "no ','");
            }
            bool b64 = false;
            for (const char *p = u; p < comma; p++)
                b64 = b64 || (*p == ';' && strncmp(p + 1, "base64", 6) == 0);
            for (const char *q = comma + 1; b64 && *q; q++) {
                if (!isalnum((unsigned char)*q) && *q != '+' && *q != '/' && *q != '=') {
                    return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %s[%d].uri: invalid base64 data",
                                           path, array, i);
                }
            }
        }
        i++;
    }
    return LANES_OK;
}

static void le32(const unsigned char *b, uint32_t *w, int n)
{
    for (int i = 0; i < n; i++)
        w[i] = (uint32_t)b[4 * i] | (uint32_t)b[4 * i + 1] << 8 | (uint32_t)b[4 * i + 2] << 16 |
               (uint32_t)b[4 * i + 3] << 24;
}

/* The sizes in a GLB 2 header (w: magic, version, total length, first
 * chunk length, its type) and of the binary chunk after it. Assimp 5.2
 * allocates each before reading a byte (a 600-byte file claiming a 1.5 GB
 * JSON chunk made it allocate that, found by fuzz_mesh_glb), so each must
 * fit in the file. 1: fine; 0: cannot tell (Assimp decides); -1: error
 * (message set). */
static int glb_sizes(const char *path, FILE *f, const uint32_t w[5], lanes_error *err)
{
    if (fseek(f, 0, SEEK_END) != 0)
        return 0;
    long size = ftell(f);
    if (size < 20)
        return 0;
    unsigned long long n = (unsigned long long)size;
    if (w[2] > n || w[3] > n - 20) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT,
                        "%s: the GLB header declares %lu bytes and a first chunk of %lu, but "
                        "the file has %llu bytes (truncated?)",
                        path, (unsigned long)w[2], (unsigned long)w[3], n);
        return -1;
    }
    /* Version 2: the binary chunk that may follow, padded to 4 bytes. */
    unsigned long long at = 20ull + ((w[3] + 3ull) & ~3ull);
    unsigned char h[8];
    uint32_t c[2];
    if (at + 8 <= w[2] && fseek(f, (long)at, SEEK_SET) == 0 &&
        fread(h, 1, sizeof h, f) == sizeof h) {
        le32(h, c, 2);
        if (c[0] > n - at - 8) {
            lanes_error_set(err, LANES_ERR_BAD_INPUT,
                            "%s: byte %llu: GLB chunk of %lu bytes, but the file ends %llu "
                            "bytes later (truncated?)",
                            path, at, (unsigned long)c[0], n - at - 8);
            return -1;
        }
    }
    return 1;
}

/* Triangles the file's primitives describe. Assimp's glTF importer drops a
 * face whose index is out of range and goes on, so a count below this one
 * means the file is broken. 1: *expected set; 0: no check possible (the
 * importer will judge); -1: error (message set). */
int mesh_gltf_expected(const char *path, unsigned long long *expected, lanes_error *err)
{
    bool glb = mesh_ext_is(path, "glb"), gltf = mesh_ext_is(path, "gltf");
    if (!glb && !gltf)
        return 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    char *text = NULL;
    size_t len = 0;
    int result = 0;
    if (glb) {
        unsigned char h[20];
        uint32_t w[5];
        if (fread(h, 1, sizeof h, f) != sizeof h) {
            lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: not a GLB file (shorter than its 20-byte header)",
                            path);
            result = -1;
            goto done;
        }
        le32(h, w, 5);
        /* Assimp would try every other importer on a .glb without the
         * magic (see known_extension). */
        if (w[0] != 0x46546C67u || w[1] != 2) {
            lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: not a GLB 2 file (%s)", path,
                            w[0] != 0x46546C67u ? "no 'glTF' magic" : "another version");
            result = -1;
            goto done;
        }
        int sz = glb_sizes(path, f, w, err);
        if (sz <= 0) {
            result = sz;
            goto done;
        }
        if (w[4] != 0x4E4F534Au || w[3] > MAX_GLTF_JSON) {
            lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: the first GLB chunk is %s", path,
                            w[4] != 0x4E4F534Au ? "not JSON" : "JSON of more than 64 MiB");
            result = -1;
            goto done;
        }
        if (fseek(f, (long)sizeof h, SEEK_SET) != 0)
            goto done;
        len = w[3];
    } else {
        if (fseek(f, 0, SEEK_END) != 0)
            goto done;
        long n = ftell(f);
        if (n < 0 || (unsigned long)n > MAX_GLTF_JSON || fseek(f, 0, SEEK_SET) != 0)
            goto done;
        len = (size_t)n;
    }
    text = malloc(len + 1);
    if (!text || fread(text, 1, len, f) != len)
        goto done;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, false);
    if (!root) {
        if (gltf) {
            size_t off = end && end >= text && end <= text + len ? (size_t)(end - text) : len;
            unsigned long line = 1;
            for (size_t i = 0; i < off; i++)
                line += text[i] == '\n';
            lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: line %lu: JSON syntax error%s", path, line,
                            off >= len ? " (unexpected end of file: truncated?)" : "");
        } else {
            lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: the JSON chunk is not valid JSON", path);
        }
        result = -1;
        goto done;
    }
    /* Both glTF importers require asset.version; a file they both refuse
     * goes to every other importer (see known_extension). */
    const cJSON *asset = cJSON_GetObjectItemCaseSensitive(root, "asset");
    const cJSON *version = cJSON_GetObjectItemCaseSensitive(asset, "version");
    const char *v = cJSON_IsString(version) ? version->valuestring : "";
    if (v[0] != '2' && (glb || strcmp(v, "1.0") != 0)) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: not a glTF file: asset.version must be \"2.0\"%s",
                        path, glb ? "" : " (or \"1.0\")");
        cJSON_Delete(root);
        result = -1;
        goto done;
    }
    if (check_data_uris(path, root, "buffers", err) != LANES_OK ||
        check_data_uris(path, root, "images", err) != LANES_OK) {
        cJSON_Delete(root);
        result = -1;
        goto done;
    }
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(root, "meshes");
    const cJSON *accessors = cJSON_GetObjectItemCaseSensitive(root, "accessors");
    unsigned long long tris = 0;
    result = 1;
    const cJSON *m;
    int mi = 0;
    cJSON_ArrayForEach(m, meshes)
    {
        const cJSON *p, *prims = cJSON_GetObjectItemCaseSensitive(m, "primitives");
        int pi = -1;
        cJSON_ArrayForEach(p, prims)
        {
            pi++;
            const cJSON *mode = cJSON_GetObjectItemCaseSensitive(p, "mode");
            const cJSON *attrs = cJSON_GetObjectItemCaseSensitive(p, "attributes");
            const cJSON *idx = cJSON_GetObjectItemCaseSensitive(p, "indices");
            long long md = mode ? gltf_int(mode, 6) : 4;
            const cJSON *pos = cJSON_GetObjectItemCaseSensitive(attrs, "POSITION");
            long long n = accessor_count(accessors, idx ? idx : pos);
            /* Assimp 5.2 sizes a strip's or fan's faces as count - 2 (a
             * line strip's as count - 1) in unsigned arithmetic, and a
             * primitive whose positions it cannot find (none, or an index
             * of 0.7) has count 0: it then allocates 64 GiB (found by
             * fuzz_mesh_gltf). Such primitives draw nothing, so they are
             * refused rather than passed on. */
            bool strip = md == 3 || md == 5 || md == 6;
            long long need = md == 3 ? 2 : strip ? 3 : 1;
            const char *bad = NULL;
            if (md < 0)
                bad = "mode is not an integer from 0 to 6";
            else if (!pos)
                bad = "no POSITION attribute";
            else if (strip && n < 0)
                bad = "a strip or fan without a valid accessor index and count";
            else if (n >= 0 && n < need)
                bad = "too few vertices for its mode";
            if (bad) {
                lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: meshes[%d].primitives[%d]: %s", path, mi, pi,
                                bad);
                result = -1;
                cJSON_Delete(root);
                goto done;
            }
            if (md < 4 || md > 6)
                continue; /* points and lines */
            if (!pos || n < 0) {
                result = 0;
                continue;
            }
            tris += (unsigned long long)(md == 4 ? n / 3 : n > 2 ? n - 2 : 0);
        }
        mi++;
    }
    *expected = tris;
    cJSON_Delete(root);
done:
    free(text);
    fclose(f);
    return result;
}
