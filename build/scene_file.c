/* JSON scene files. cJSON parses; everything it does not check (keys,
 * types, ranges, references) is checked here, and because cJSON keeps no
 * positions, the line of a bad key is found again by walking the raw text
 * along the key's JSON path.
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L /* stat: "no such file" vs. "is a directory" */

#include "build/scene_file.h"

#include "build/memory_limit.h"
#include "build/mesh_import.h"
#include "build/mesh_ops.h"
#include "build/scenes_builtin.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAX_SCENE_FILE (64u << 20) /* bytes; a scene file is a list, not geometry */
#define MAX_DEPTH 16

typedef struct path_elem {
    const char *key; /* NULL: an array index */
    int index;
} path_elem;

typedef struct ctx {
    const char *name; /* the file, for messages */
    const char *text;
    size_t len;
    const char *base_dir; /* for relative mesh paths */
    lanes_scene *s;
    lanes_error *err;
    path_elem path[MAX_DEPTH];
    int depth;
} ctx;

/* ---- where a JSON path is in the raw text ---- */

static size_t skip_ws(const char *t, size_t n, size_t i)
{
    while (i < n && (t[i] == ' ' || t[i] == '\t' || t[i] == '\n' || t[i] == '\r'))
        i++;
    return i;
}

/* t[i] is the opening quote; returns the index after the closing one. */
static size_t skip_string(const char *t, size_t n, size_t i)
{
    for (i++; i < n && t[i] != '"'; i++)
        if (t[i] == '\\')
            i++;
    return i < n ? i + 1 : n;
}

static size_t skip_value(const char *t, size_t n, size_t i)
{
    i = skip_ws(t, n, i);
    if (i >= n)
        return n;
    if (t[i] == '"')
        return skip_string(t, n, i);
    if (t[i] == '{' || t[i] == '[') {
        int d = 0;
        while (i < n) {
            if (t[i] == '"') {
                i = skip_string(t, n, i);
                continue;
            }
            if (t[i] == '{' || t[i] == '[')
                d++;
            else if (t[i] == '}' || t[i] == ']')
                d--;
            i++;
            if (d == 0)
                break;
        }
        return i;
    }
    while (i < n && !strchr(",}] \t\r\n", t[i]))
        i++;
    return i;
}

/* Offset of the last path element (the key's opening quote, or the array
 * element), or SIZE_MAX when the text does not lead there (e.g. a key
 * written with escapes). */
static size_t locate(const char *t, size_t n, const path_elem *path, int depth)
{
    size_t i = skip_ws(t, n, 0);
    for (int d = 0; d < depth; d++) {
        if (path[d].key) {
            if (i >= n || t[i] != '{')
                return SIZE_MAX;
            i++;
            size_t klen = strlen(path[d].key);
            for (;;) {
                i = skip_ws(t, n, i);
                if (i >= n || t[i] != '"')
                    return SIZE_MAX;
                size_t ks = i + 1, ke = skip_string(t, n, i);
                bool match = ke - 1 - ks == klen && memcmp(t + ks, path[d].key, klen) == 0;
                i = skip_ws(t, n, ke);
                if (i >= n || t[i] != ':')
                    return SIZE_MAX;
                i = skip_ws(t, n, i + 1);
                if (match) {
                    if (d == depth - 1)
                        return ks - 1;
                    break;
                }
                i = skip_ws(t, n, skip_value(t, n, i));
                if (i < n && t[i] == ',')
                    i++;
            }
        } else {
            if (i >= n || t[i] != '[')
                return SIZE_MAX;
            i++;
            for (int k = 0; k < path[d].index; k++) {
                i = skip_ws(t, n, skip_value(t, n, i));
                if (i >= n || t[i] != ',')
                    return SIZE_MAX;
                i++;
            }
            i = skip_ws(t, n, i);
        }
    }
    return i;
}

/* The offset of the first \u0000 escape inside a JSON string, or n.
 * cJSON decodes it to a NUL byte, which silently ends the key or value it
 * is in ("color\u0000x" would read as "color"). Escaped backslashes are
 * skipped, so "\\u0000" (a backslash, then "u0000") is not one. */
static size_t find_nul_escape(const char *t, size_t n)
{
    bool in_string = false;
    for (size_t i = 0; i < n; i++) {
        if (!in_string) {
            in_string = t[i] == '"';
        } else if (t[i] == '"') {
            in_string = false;
        } else if (t[i] == '\\' && i + 1 < n) {
            if (t[i + 1] == 'u' && i + 5 < n && memcmp(t + i + 2, "0000", 4) == 0) return i;
            i++; /* the escaped character */
        }
    }
    return n;
}

static unsigned long line_of(const char *t, size_t n, size_t off)
{
    unsigned long line = 1;
    for (size_t i = 0; i < off && i < n; i++)
        line += t[i] == '\n';
    return line;
}

/* ---- messages ---- */

static void push_key(ctx *c, const char *key)
{
    if (c->depth < MAX_DEPTH)
        c->path[c->depth] = (path_elem){key, 0};
    c->depth++;
}

static void push_index(ctx *c, int index)
{
    if (c->depth < MAX_DEPTH)
        c->path[c->depth] = (path_elem){NULL, index};
    c->depth++;
}

static void pop(ctx *c)
{
    c->depth--;
}

#if defined(__GNUC__)
#define PRINTF_LIKE(f, a) __attribute__((format(printf, f, a)))
#else
#define PRINTF_LIKE(f, a)
#endif

static bool fail(ctx *c, const char *fmt, ...) PRINTF_LIKE(2, 3);

/* "file: line N: json.path: what"; the line is left out when the text does
 * not lead to the path. Always returns false, for `return fail(...)`. */
static bool fail_status(ctx *c, lanes_status status, const char *what)
{
    char path[160] = "";
    int depth = c->depth < MAX_DEPTH ? c->depth : MAX_DEPTH;
    for (int d = 0; d < depth; d++) {
        size_t l = strlen(path);
        if (c->path[d].key)
            snprintf(path + l, sizeof path - l, "%s%s", d ? "." : "", c->path[d].key);
        else
            snprintf(path + l, sizeof path - l, "[%d]", c->path[d].index);
    }
    size_t off = locate(c->text, c->len, c->path, depth);
    char where[48] = "";
    if (off != SIZE_MAX)
        snprintf(where, sizeof where, "line %lu: ", line_of(c->text, c->len, off));
    lanes_error_set(c->err, status, "%s: %s%s%s%s", c->name, where, path, path[0] ? ": " : "", what);
    return false;
}

static bool fail(ctx *c, const char *fmt, ...)
{
    char what[320];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return fail_status(c, LANES_ERR_BAD_INPUT, what);
}

/* A callee's error (a mesh that would not load, a scene out of memory) at
 * the current place in the file, with the callee's status. */
static bool fail_from(ctx *c, const lanes_error *sub)
{
    return fail_status(c, sub->status, sub->message);
}

/* ---- typed getters ---- */

static const char *type_name(const cJSON *v)
{
    if (cJSON_IsNumber(v))
        return "a number";
    if (cJSON_IsString(v))
        return "a string";
    if (cJSON_IsBool(v))
        return "a boolean";
    if (cJSON_IsNull(v))
        return "null";
    if (cJSON_IsArray(v))
        return "an array";
    if (cJSON_IsObject(v))
        return "an object";
    return "something else";
}

/* Unknown and duplicate keys. "comment" is allowed everywhere. */
static bool check_keys(ctx *c, const cJSON *obj, const char *const *allowed, const char *what)
{
    for (const cJSON *it = obj->child; it; it = it->next) {
        bool ok = strcmp(it->string, "comment") == 0;
        for (int i = 0; allowed[i] && !ok; i++)
            ok = strcmp(it->string, allowed[i]) == 0;
        if (!ok) {
            char valid[256] = "";
            for (int i = 0; allowed[i]; i++) {
                size_t l = strlen(valid);
                snprintf(valid + l, sizeof valid - l, "%s%s", i ? ", " : "", allowed[i]);
            }
            push_key(c, it->string);
            fail(c, "unknown key '%s' in %s (valid: %s)", it->string, what, valid);
            pop(c);
            return false;
        }
        for (const cJSON *p = obj->child; p != it; p = p->next) {
            if (strcmp(p->string, it->string) == 0) {
                push_key(c, it->string);
                fail(c, "duplicate key '%s'", it->string);
                pop(c);
                return false;
            }
        }
    }
    return true;
}

static const cJSON *member(const cJSON *obj, const char *key)
{
    return cJSON_GetObjectItemCaseSensitive(obj, key);
}

static bool missing(ctx *c, const char *key, const char *what)
{
    return fail(c, "missing required key '%s' in %s", key, what);
}

static bool finite_float(double v)
{
    return isfinite(v) && fabs(v) <= FLT_MAX;
}

static bool get_number(ctx *c, const cJSON *v, double lo, double hi, double *out)
{
    if (!cJSON_IsNumber(v))
        return fail(c, "expected a number, found %s", type_name(v));
    double d = v->valuedouble;
    if (!finite_float(d) || d < lo || d > hi)
        return fail(c, "%g is out of range [%g, %g]", d, lo, hi);
    *out = d;
    return true;
}

static bool get_int(ctx *c, const cJSON *v, int lo, int hi, int *out)
{
    double d = 0.0;
    if (!get_number(c, v, lo, hi, &d))
        return false;
    if (d != floor(d))
        return fail(c, "expected an integer, found %g", d);
    *out = (int)d;
    return true;
}

static bool get_vec3(ctx *c, const cJSON *v, double out[3])
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3)
        return fail(c, "expected an array of 3 numbers, found %s",
                    cJSON_IsArray(v) ? "an array of another length" : type_name(v));
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, i++) {
        push_index(c, i);
        bool ok = get_number(c, e, -FLT_MAX, FLT_MAX, &out[i]);
        pop(c);
        if (!ok)
            return false;
    }
    return true;
}

/* A color: [r, g, b] or one number for grey; finite and >= 0. */
static bool get_color(ctx *c, const cJSON *v, float out[3])
{
    double d[3] = {0, 0, 0};
    if (cJSON_IsNumber(v)) {
        if (!get_number(c, v, 0.0, FLT_MAX, &d[0]))
            return false;
        d[1] = d[2] = d[0];
    } else {
        if (!get_vec3(c, v, d))
            return false;
        for (int i = 0; i < 3; i++)
            if (d[i] < 0.0)
                return fail(c, "color components must be >= 0, found %g", d[i]);
    }
    for (int i = 0; i < 3; i++)
        out[i] = (float)d[i];
    return true;
}

static bool get_string(ctx *c, const cJSON *v, const char **out)
{
    if (!cJSON_IsString(v) || !v->valuestring)
        return fail(c, "expected a string, found %s", type_name(v));
    *out = v->valuestring;
    return true;
}

static bool get_bool(ctx *c, const cJSON *v, bool *out)
{
    if (!cJSON_IsBool(v))
        return fail(c, "expected true or false, found %s", type_name(v));
    *out = cJSON_IsTrue(v);
    return true;
}

static void to_float3(const double in[3], float out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = (float)in[i];
}

/* ---- sections ---- */

static bool parse_camera(ctx *c, const cJSON *cam)
{
    static const char *const keys[] = {"eye", "target", "up", "fov", "width", "height", NULL};
    if (!cJSON_IsObject(cam))
        return fail(c, "expected an object, found %s", type_name(cam));
    if (!check_keys(c, cam, keys, "the camera"))
        return false;
    lanes_camera *k = &c->s->camera;
    double v[3];
    const cJSON *e;
    if (!(e = member(cam, "eye")))
        return missing(c, "eye", "the camera");
    push_key(c, "eye");
    bool ok = get_vec3(c, e, v);
    pop(c);
    if (!ok)
        return false;
    to_float3(v, k->eye);
    if (!(e = member(cam, "target")))
        return missing(c, "target", "the camera");
    push_key(c, "target");
    ok = get_vec3(c, e, v);
    pop(c);
    if (!ok)
        return false;
    to_float3(v, k->target);
    if ((e = member(cam, "up"))) {
        push_key(c, "up");
        ok = get_vec3(c, e, v);
        pop(c);
        if (!ok)
            return false;
        to_float3(v, k->up);
    }
    if ((e = member(cam, "fov"))) {
        double f;
        push_key(c, "fov");
        ok = get_number(c, e, 0.0, 180.0, &f) &&
             (f > 0.0 && f < 180.0 ? true : fail(c, "fov must be strictly between 0 and 180"));
        pop(c);
        if (!ok)
            return false;
        k->fov_y_degrees = (float)f;
    }
    const char *dims[2] = {"width", "height"};
    int *dst[2] = {&k->width, &k->height};
    for (int i = 0; i < 2; i++) {
        if ((e = member(cam, dims[i]))) {
            push_key(c, dims[i]);
            ok = get_int(c, e, 1, LANES_CAMERA_MAX_SIDE, dst[i]);
            pop(c);
            if (!ok)
                return false;
        }
    }
    double f[3], cr[3];
    for (int a = 0; a < 3; a++)
        f[a] = (double)k->target[a] - k->eye[a];
    cr[0] = f[1] * k->up[2] - f[2] * k->up[1];
    cr[1] = f[2] * k->up[0] - f[0] * k->up[2];
    cr[2] = f[0] * k->up[1] - f[1] * k->up[0];
    if (f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0)
        return fail(c, "eye and target are the same point");
    if (cr[0] == 0.0 && cr[1] == 0.0 && cr[2] == 0.0)
        return fail(c, "up is zero or parallel to the view direction");
    return true;
}

/* A reflectance: a color that is a fraction of the light, each channel in
 * [0, 1]. */
static bool get_reflectance(ctx *c, const cJSON *v, float out[3])
{
    if (!get_color(c, v, out)) return false;
    for (int i = 0; i < 3; i++)
        if (out[i] > 1.0f) return fail(c, "a reflectance lies in [0, 1], found %g", (double)out[i]);
    return true;
}

static bool parse_texture(ctx *c, const cJSON *t, lanes_material *mat)
{
    static const char *const keys[] = {"type", "scale", "colors", NULL};
    static const char *const names[] = {"checker", "noise", "marble", "wood"};
    if (!cJSON_IsObject(t)) return fail(c, "expected an object, found %s", type_name(t));
    if (!check_keys(c, t, keys, "a texture")) return false;
    const cJSON *e;
    const char *type = NULL;
    if (!(e = member(t, "type"))) return missing(c, "type", "a texture");
    push_key(c, "type");
    bool ok = get_string(c, e, &type);
    for (int i = 0; ok && i < 4 && mat->texture == LANES_MAT_TEXTURE_NONE; i++)
        if (strcmp(type, names[i]) == 0) mat->texture = (lanes_material_texture)(LANES_MAT_TEXTURE_CHECKER + i);
    if (ok && mat->texture == LANES_MAT_TEXTURE_NONE)
        ok = fail(c, "unknown texture type '%s' (valid: checker, noise, marble, wood)", type);
    pop(c);
    if (!ok) return false;
    double scale = 1.0;
    if ((e = member(t, "scale"))) {
        push_key(c, "scale");
        ok = get_number(c, e, 1e-6, 1e6, &scale);
        pop(c);
        if (!ok) return false;
    }
    mat->texture_scale = (float)scale;
    if (!(e = member(t, "colors"))) return missing(c, "colors", "a texture");
    push_key(c, "colors");
    if (!cJSON_IsArray(e) || cJSON_GetArraySize(e) != 2)
        ok = fail(c, "expected an array of two colors");
    for (int i = 0; ok && i < 2; i++) {
        push_index(c, i);
        ok = get_reflectance(c, cJSON_GetArrayItem(e, i), mat->texture_colors[i]);
        pop(c);
    }
    pop(c);
    for (int k = 0; ok && k < 3; k++) mat->color[k] = 0.5f * (mat->texture_colors[0][k] + mat->texture_colors[1][k]);
    return ok;
}

/* The material types a scene file names: their kinds, the keys each takes
 * and the grey their color has when none is given. */
typedef struct {
    const char *type;
    lanes_material_kind kind;
    float grey;
    const char *const *keys;
} material_type;

static const char *const k_diffuse[] = {"type", "color", "texture", "emission", NULL};
static const char *const k_mirror[] = {"type", "color", NULL};
static const char *const k_glass[] = {"type", "color", "ior", "roughness", NULL};
static const char *const k_emissive[] = {"type", "emission", NULL};
static const char *const k_conductor[] = {"type", "f0", "roughness", NULL};
static const char *const k_plastic[] = {"type", "color", "texture", "roughness", NULL};

static const material_type material_types[] = {
    {"diffuse", LANES_MAT_DIFFUSE, 0.8f, k_diffuse},       {"mirror", LANES_MAT_MIRROR, 1.0f, k_mirror},
    {"glass", LANES_MAT_GLASS, 1.0f, k_glass},             {"emissive", LANES_MAT_EMISSIVE, 0.0f, k_emissive},
    {"conductor", LANES_MAT_CONDUCTOR, 0.9f, k_conductor}, {"plastic", LANES_MAT_PLASTIC, 0.8f, k_plastic},
};

/* The keys every type may take but `type`, each parsed where present. */
static bool parse_material_key(ctx *c, const cJSON *e, const char *key, lanes_material *mat)
{
    double d;
    if (strcmp(key, "color") == 0) return get_reflectance(c, e, mat->color);
    if (strcmp(key, "f0") == 0) {
        if (!get_reflectance(c, e, mat->f0)) return false;
        memcpy(mat->color, mat->f0, sizeof mat->color); /* the Whitted renderers' mirror */
        return true;
    }
    if (strcmp(key, "emission") == 0) return get_color(c, e, mat->emission);
    if (strcmp(key, "texture") == 0) return parse_texture(c, e, mat);
    if (strcmp(key, "ior") == 0) {
        if (!get_number(c, e, 0.01, 10.0, &d)) return false;
        mat->ior = (float)d;
        return true;
    }
    if (strcmp(key, "roughness") == 0) {
        if (!get_number(c, e, 0.0, 1.0, &d)) return false;
        mat->roughness = (float)d;
        return true;
    }
    return true; /* type, comment */
}

static bool parse_material(ctx *c, const cJSON *m)
{
    const char *name = m->string;
    if (!*name || strlen(name) >= sizeof c->s->materials[0].name)
        return fail(c, "a material name must have 1 to %zu characters",
                    sizeof c->s->materials[0].name - 1);
    if (name[0] == '@')
        return fail(c, "material names starting with '@' are reserved");
    if (!cJSON_IsObject(m))
        return fail(c, "expected an object, found %s", type_name(m));
    const cJSON *t = member(m, "type");
    const char *type = NULL;
    if (!t)
        return missing(c, "type", "a material");
    push_key(c, "type");
    bool ok = get_string(c, t, &type);
    const material_type *mt = NULL;
    for (size_t i = 0; ok && !mt && i < sizeof material_types / sizeof *material_types; i++)
        if (strcmp(type, material_types[i].type) == 0) mt = &material_types[i];
    if (ok && !mt)
        ok = fail(c, "unknown material type '%s' (valid: diffuse, mirror, glass, emissive, conductor, plastic)", type);
    pop(c);
    if (!ok)
        return false;
    char what[96];
    snprintf(what, sizeof what, "a %s material", type);
    if (!check_keys(c, m, mt->keys, what))
        return false;
    if (member(m, "color") && member(m, "texture"))
        return fail(c, "a material takes a color or a texture, not both");
    if (mt->kind == LANES_MAT_EMISSIVE && !member(m, "emission"))
        return missing(c, "emission", "an emissive material");
    lanes_material mat;
    memset(&mat, 0, sizeof mat);
    snprintf(mat.name, sizeof mat.name, "%s", name);
    mat.kind = mt->kind;
    mat.ior = 1.5f;
    mat.roughness = mt->kind == LANES_MAT_GLASS ? 0.0f : 0.3f;
    for (int k = 0; k < 3; k++) mat.color[k] = mat.f0[k] = mt->grey;
    for (const cJSON *e = m->child; ok && e; e = e->next) {
        push_key(c, e->string);
        ok = parse_material_key(c, e, e->string, &mat);
        pop(c);
    }
    if (!ok)
        return false;
    lanes_error sub;
    if (lanes_scene_add_material(c->s, &mat, NULL, &sub) != LANES_OK) return fail_from(c, &sub);
    return true;
}

static bool parse_rotation(ctx *c, const cJSON *r, lanes_xform *out)
{
    if (cJSON_IsArray(r)) {
        double e[3];
        if (!get_vec3(c, r, e))
            return false;
        /* Euler angles in degrees, applied about x, then y, then z. */
        static const double ax[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        lanes_xform_identity(out);
        for (int i = 0; i < 3; i++) {
            lanes_xform ri;
            lanes_xform_rotation(&ri, ax[i], e[i]);
            lanes_xform_mul(out, &ri, out);
        }
        return true;
    }
    if (!cJSON_IsObject(r))
        return fail(c,
                    "expected [x, y, z] degrees or {\"axis\": [..], \"angle\": degrees}, "
                    "found %s",
                    type_name(r));
    static const char *const keys[] = {"axis", "angle", NULL};
    if (!check_keys(c, r, keys, "a rotation"))
        return false;
    const cJSON *axis = member(r, "axis"), *angle = member(r, "angle");
    if (!axis)
        return missing(c, "axis", "a rotation");
    if (!angle)
        return missing(c, "angle", "a rotation");
    double a[3], deg;
    push_key(c, "axis");
    bool ok = get_vec3(c, axis, a) &&
              (a[0] != 0.0 || a[1] != 0.0 || a[2] != 0.0 ? true : fail(c, "the axis is zero"));
    pop(c);
    if (!ok)
        return false;
    push_key(c, "angle");
    ok = get_number(c, angle, -FLT_MAX, FLT_MAX, &deg);
    pop(c);
    if (!ok)
        return false;
    lanes_xform_rotation(out, a, deg);
    return true;
}

static bool parse_object(ctx *c, const cJSON *o)
{
    static const char *const keys[] = {"name",   "mesh",  "builtin", "material",  "translate",
                                       "rotate", "scale", "detail",  "normalize", NULL};
    if (!cJSON_IsObject(o))
        return fail(c, "expected an object, found %s", type_name(o));
    if (!check_keys(c, o, keys, "an object"))
        return false;
    const cJSON *mesh = member(o, "mesh"), *builtin = member(o, "builtin"), *e;
    if (!mesh == !builtin)
        return fail(c, "an object needs exactly one of 'mesh' (a file) or 'builtin' (%s)",
                    lanes_builtin_object_names());
    const char *label = NULL;
    bool ok = true;
    if ((e = member(o, "name"))) {
        push_key(c, "name");
        ok = get_string(c, e, &label);
        pop(c);
        if (!ok)
            return false;
    }
    const char *matname = NULL;
    if (!(e = member(o, "material")))
        return missing(c, "material", "an object");
    push_key(c, "material");
    ok = get_string(c, e, &matname);
    long mat = ok ? lanes_scene_find_material(c->s, matname) : -1;
    if (ok && mat < 0) {
        char defined[256] = "";
        for (size_t i = 0; i < c->s->material_count; i++) {
            if (c->s->materials[i].name[0] == '@')
                continue;
            size_t l = strlen(defined);
            snprintf(defined + l, sizeof defined - l, "%s%s", l ? ", " : "",
                     c->s->materials[i].name);
        }
        ok = fail(c, "undefined material '%s' (defined: %s)", matname,
                  defined[0] ? defined : "none");
    }
    pop(c);
    if (!ok)
        return false;
    int detail = -1;
    if ((e = member(o, "detail"))) {
        push_key(c, "detail");
        ok = get_int(c, e, 0, 4096, &detail);
        pop(c);
        if (!ok)
            return false;
    }
    bool normalize = false;
    if ((e = member(o, "normalize"))) {
        push_key(c, "normalize");
        ok = get_bool(c, e, &normalize) &&
             (mesh ? true
                   : fail(c, "'normalize' applies to 'mesh' objects (built-in meshes "
                             "are always normalized)"));
        pop(c);
        if (!ok)
            return false;
    }
    double t[3] = {0, 0, 0}, sc[3] = {1, 1, 1};
    lanes_xform rot;
    lanes_xform_identity(&rot);
    if ((e = member(o, "translate"))) {
        push_key(c, "translate");
        ok = get_vec3(c, e, t);
        pop(c);
        if (!ok)
            return false;
    }
    if ((e = member(o, "rotate"))) {
        push_key(c, "rotate");
        ok = parse_rotation(c, e, &rot);
        pop(c);
        if (!ok)
            return false;
    }
    if ((e = member(o, "scale"))) {
        push_key(c, "scale");
        if (cJSON_IsNumber(e)) {
            ok = get_number(c, e, -FLT_MAX, FLT_MAX, &sc[0]);
            sc[1] = sc[2] = sc[0];
        } else {
            ok = get_vec3(c, e, sc);
        }
        if (ok && (sc[0] == 0.0 || sc[1] == 0.0 || sc[2] == 0.0))
            ok = fail(c, "a scale of 0 flattens the object");
        pop(c);
        if (!ok)
            return false;
    }
    lanes_mesh m;
    lanes_error sub;
    if (mesh) {
        const char *file = NULL;
        push_key(c, "mesh");
        ok = get_string(c, mesh, &file);
        char full[4096];
        if (ok) {
            int k = file[0] == '/' || !c->base_dir
                        ? snprintf(full, sizeof full, "%s", file)
                        : snprintf(full, sizeof full, "%s/%s", c->base_dir, file);
            if (k < 0 || (size_t)k >= sizeof full)
                ok = fail(c, "path too long");
        }
        if (ok && detail > 4)
            ok = fail(c, "'detail' for a mesh file is Loop subdivision steps: at most 4");
        if (ok && lanes_mesh_read(full, &m, &sub) != LANES_OK) ok = fail_from(c, &sub);
        for (int i = 0; ok && i < detail; i++) {
            lanes_mesh fine;
            ok = lanes_mesh_subdivide(&m, &fine, &sub) == LANES_OK || fail_from(c, &sub);
            lanes_mesh_free(&m);
            if (ok)
                m = fine;
        }
        if (ok && normalize) {
            lanes_xform nx;
            lanes_mesh_normalizing_xform(&m, &nx);
            for (size_t v = 0; v < m.vertex_count; v++)
                lanes_xform_apply(&nx, m.positions + 3 * v, m.positions + 3 * v);
        }
        pop(c);
    } else {
        const char *name = NULL;
        push_key(c, "builtin");
        ok = get_string(c, builtin, &name) &&
             (lanes_builtin_object(name, detail, &m, &sub) == LANES_OK || fail_from(c, &sub));
        pop(c);
    }
    if (!ok)
        return false;
    lanes_xform x;
    lanes_xform_trs(&x, t, &rot, sc);
    ok = lanes_scene_add_mesh(c->s, &m, &x, (uint32_t)mat, label ? label : "object", &sub) == LANES_OK ||
         fail_from(c, &sub);
    lanes_mesh_free(&m);
    return ok;
}

/* Mesh files already pre-checked by check_declared_size, so that a file
 * used by many objects is read once there. */
typedef struct faces_seen {
    const char *file[64];
    double faces[64];
    int n;
} faces_seen;

/* The triangles an object declares, before anything is read or made: a
 * built-in's count, a mesh file's declared faces (each at least one
 * triangle), times 4 per subdivision step. 0 for an object that is not
 * well formed, which parse_object then refuses with the reason. */
static double declared_triangles(const ctx *c, const cJSON *o, faces_seen *seen)
{
    const cJSON *mesh = member(o, "mesh"), *builtin = member(o, "builtin"), *detail = member(o, "detail");
    int d = -1;
    if (detail && cJSON_IsNumber(detail) && detail->valuedouble >= 0 && detail->valuedouble <= 4096)
        d = (int)detail->valuedouble;
    if (builtin && cJSON_IsString(builtin)) return lanes_builtin_object_triangles(builtin->valuestring, d);
    if (!mesh || !cJSON_IsString(mesh) || d > 4) return 0;
    const char *file = mesh->valuestring;
    int i = 0;
    while (i < seen->n && strcmp(seen->file[i], file) != 0) i++;
    double faces = 0;
    if (i < seen->n) {
        faces = seen->faces[i];
    } else {
        char full[4096];
        int k = file[0] == '/' || !c->base_dir ? snprintf(full, sizeof full, "%s", file)
                                               : snprintf(full, sizeof full, "%s/%s", c->base_dir, file);
        lanes_error ignored;
        if (k < 0 || (size_t)k >= sizeof full || lanes_mesh_declared_faces(full, &faces, &ignored) != LANES_OK)
            faces = 0;
        if (seen->n < 64) seen->file[seen->n] = file, seen->faces[seen->n++] = faces;
    }
    return faces * pow(4.0, d < 0 ? 0 : d);
}

/* Refuses a scene whose objects together declare more triangles than the
 * memory holds, before the first is made: otherwise 200 spheres of detail 8
 * were made one by one for over a minute, to 3 GB, until the running count
 * crossed the budget at the 62nd. */
static bool check_declared_size(ctx *c, const cJSON *objs)
{
    if (!c->s->budget_note[0]) return true;
    double total = 0;
    faces_seen seen = {.n = 0};
    for (const cJSON *o = objs->child; o; o = o->next)
        if (cJSON_IsObject(o)) total += declared_triangles(c, o, &seen);
    if (total <= (double)c->s->triangle_budget) return true;
    char bytes[32], what[320];
    lanes_memory_size_text(bytes, sizeof bytes,
                           total * (double)(LANES_SCENE_BYTES_PER_TRIANGLE + LANES_ACCEL_BYTES_PER_TRIANGLE));
    snprintf(what, sizeof what, "the %d objects declare %.0f triangles, a scene (to load and trace) of about %s; %s",
             cJSON_GetArraySize(objs), total, bytes, c->s->budget_note);
    return fail_status(c, LANES_ERR_OUT_OF_MEMORY, what);
}

static bool parse_light(ctx *c, const cJSON *l)
{
    static const char *const k_point[] = {"type", "position", "intensity", NULL};
    static const char *const k_area[] = {"type",     "corner",  "edge_u", "edge_v",
                                         "emission", "visible", NULL};
    if (!cJSON_IsObject(l))
        return fail(c, "expected an object, found %s", type_name(l));
    const cJSON *t = member(l, "type"), *e;
    const char *type = NULL;
    if (!t)
        return missing(c, "type", "a light");
    push_key(c, "type");
    bool ok = get_string(c, t, &type);
    bool point = ok && strcmp(type, "point") == 0, area = ok && strcmp(type, "area") == 0;
    if (ok && !point && !area)
        ok = fail(c, "unknown light type '%s' (valid: point, area)", type);
    pop(c);
    if (!ok)
        return false;
    if (!check_keys(c, l, point ? k_point : k_area, point ? "a point light" : "an area light"))
        return false;
    double v[3];
    lanes_error sub;
    if (point) {
        lanes_point_light pl;
        if (!(e = member(l, "position")))
            return missing(c, "position", "a point light");
        push_key(c, "position");
        ok = get_vec3(c, e, v);
        pop(c);
        if (!ok)
            return false;
        to_float3(v, pl.position);
        if (!(e = member(l, "intensity")))
            return missing(c, "intensity", "a point light");
        push_key(c, "intensity");
        ok = get_color(c, e, pl.intensity);
        pop(c);
        if (!ok)
            return false;
        return lanes_scene_add_point_light(c->s, &pl, &sub) == LANES_OK || fail_from(c, &sub);
    }
    lanes_area_light al;
    const char *vk[3] = {"corner", "edge_u", "edge_v"};
    float *dst[3] = {al.corner, al.edge_u, al.edge_v};
    for (int i = 0; i < 3; i++) {
        if (!(e = member(l, vk[i])))
            return missing(c, vk[i], "an area light");
        push_key(c, vk[i]);
        ok = get_vec3(c, e, v);
        pop(c);
        if (!ok)
            return false;
        to_float3(v, dst[i]);
    }
    if (!(e = member(l, "emission")))
        return missing(c, "emission", "an area light");
    push_key(c, "emission");
    ok = get_color(c, e, al.emission);
    pop(c);
    if (!ok)
        return false;
    bool visible = true;
    if ((e = member(l, "visible"))) {
        push_key(c, "visible");
        ok = get_bool(c, e, &visible);
        pop(c);
        if (!ok)
            return false;
    }
    double u[3] = {al.edge_u[0], al.edge_u[1], al.edge_u[2]},
           w[3] = {al.edge_v[0], al.edge_v[1], al.edge_v[2]};
    double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0)
        return fail(c, "edge_u and edge_v are zero or parallel: the light has no area");
    return lanes_scene_add_area_light_quad(c->s, &al, visible, &sub) == LANES_OK || fail_from(c, &sub);
}

static bool parse_scene(ctx *c, const cJSON *root)
{
    if (!cJSON_IsObject(root))
        return fail(c, "the top level must be an object, found %s", type_name(root));
    static const char *const keys[] = {"name",   "camera",   "materials", "objects",
                                       "lights", "accuracy", NULL};
    if (!check_keys(c, root, keys, "the scene"))
        return false;
    const cJSON *e;
    bool ok;
    if ((e = member(root, "name"))) {
        const char *name = NULL;
        push_key(c, "name");
        ok = get_string(c, e, &name);
        pop(c);
        if (!ok)
            return false;
        snprintf(c->s->name, sizeof c->s->name, "%s", name);
    }
    if ((e = member(root, "accuracy"))) {
        const char *mode = NULL;
        push_key(c, "accuracy");
        ok = get_string(c, e, &mode);
        if (ok) {
            c->s->accuracy = lanes_accuracy_from_name(mode);
            ok = c->s->accuracy >= 0 ||
                 fail(c, "unknown accuracy mode '%s' (valid: fast, default, robust)", mode);
        }
        pop(c);
        if (!ok)
            return false;
    }
    const cJSON *mats = member(root, "materials");
    if (!mats)
        return missing(c, "materials", "the scene");
    push_key(c, "materials");
    ok = cJSON_IsObject(mats) ||
         fail(c, "expected an object of named materials, found %s", type_name(mats));
    for (const cJSON *m = ok ? mats->child : NULL; m && ok; m = m->next) {
        for (const cJSON *p = mats->child; p != m && ok; p = p->next)
            if (strcmp(p->string, m->string) == 0) {
                push_key(c, m->string);
                ok = fail(c, "material '%s' is defined twice", m->string);
                pop(c);
            }
        push_key(c, m->string);
        ok = ok && parse_material(c, m);
        pop(c);
    }
    pop(c);
    if (!ok)
        return false;
    const cJSON *objs = member(root, "objects");
    if (!objs)
        return missing(c, "objects", "the scene");
    push_key(c, "objects");
    ok = (cJSON_IsArray(objs) || fail(c, "expected an array, found %s", type_name(objs))) &&
         (cJSON_GetArraySize(objs) > 0 || fail(c, "no objects")) && check_declared_size(c, objs);
    int i = 0;
    for (const cJSON *o = ok ? objs->child : NULL; o && ok; o = o->next, i++) {
        push_index(c, i);
        ok = parse_object(c, o);
        pop(c);
    }
    pop(c);
    if (!ok)
        return false;
    if ((e = member(root, "lights"))) {
        push_key(c, "lights");
        ok = cJSON_IsArray(e) || fail(c, "expected an array, found %s", type_name(e));
        i = 0;
        for (const cJSON *l = ok ? e->child : NULL; l && ok; l = l->next, i++) {
            push_index(c, i);
            ok = parse_light(c, l);
            pop(c);
        }
        pop(c);
        if (!ok)
            return false;
    }
    if ((e = member(root, "camera"))) {
        push_key(c, "camera");
        ok = parse_camera(c, e);
        pop(c);
        if (!ok)
            return false;
    } else {
        lanes_scene_frame_camera(c->s);
    }
    lanes_error sub;
    if (lanes_scene_validate(c->s, &sub) != LANES_OK) return fail_from(c, &sub);
    return true;
}

lanes_status lanes_scene_file_parse(const char *text, size_t len, const char *name, const char *base_dir,
                                    lanes_scene *out, lanes_error *err)
{
    lanes_status status;
    /* the parser's steps report through err (in ctx), so it must exist */
    lanes_error local;
    if (!err) err = &local;
    lanes_scene_init(out);
    if ((status = lanes_scene_limit_to_memory(out, err)) != LANES_OK) return status;
    /* A UTF-8 byte order mark is legal in a file but not to cJSON. */
    size_t skip = len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
    ctx c = {name, text + skip, len - skip, base_dir, out, err, {{0}}, 0};
    size_t first = skip_ws(c.text, c.len, 0);
    if (first == c.len) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: empty file", name);
    }
    size_t nul = find_nul_escape(c.text, c.len);
    if (nul < c.len) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "%s: line %lu: a string holds \\u0000, which would cut it short; names, "
                               "keys and paths cannot contain NUL",
                               name, line_of(c.text, c.len, nul));
    }
    const char *end = NULL;
    /* Trailing content is checked here rather than by cJSON's
     * require_null_terminated, which wants the NUL inside `len`. */
    cJSON *root = cJSON_ParseWithLengthOpts(c.text, c.len, &end, false);
    if (root && end && skip_ws(c.text, c.len, (size_t)(end - c.text)) < c.len) {
        cJSON_Delete(root);
        root = NULL;
        end = c.text + skip_ws(c.text, c.len, (size_t)(end - c.text));
    }
    if (!root) {
        size_t off = end && end >= c.text && end <= c.text + c.len ? (size_t)(end - c.text) : 0;
        size_t bol = off;
        while (bol > 0 && c.text[bol - 1] != '\n')
            bol--;
        char near[32] = "";
        size_t k = 0;
        for (size_t i = off; i < c.len && k + 1 < sizeof near && c.text[i] != '\n'; i++)
            near[k++] = (c.text[i] >= ' ' && c.text[i] < 127) ? c.text[i] : '?';
        near[k] = '\0';
        if (skip_ws(c.text, c.len, off) >= c.len) {
            /* The line of the last thing in the file, not of the blank
             * after it. */
            size_t last = off < c.len ? off : c.len;
            while (last > 0 && c.text[last - 1] != 0 && strchr(" \t\r\n", c.text[last - 1]))
                last--;
            return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                   "%s: line %lu: JSON syntax error: unexpected end of file "
                                   "(truncated?)",
                                   name, line_of(c.text, c.len, last > 0 ? last - 1 : 0));
        }
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "%s: line %lu, column %zu: JSON syntax error near '%s'", name,
                               line_of(c.text, c.len, off), off - bol + 1, near);
    }
    const char *slash = strrchr(name, '/');
    snprintf(out->name, sizeof out->name, "%s", slash ? slash + 1 : name);
    char *dot = strrchr(out->name, '.');
    if (dot && dot != out->name)
        *dot = '\0';
    bool ok = parse_scene(&c, root);
    cJSON_Delete(root);
    if (!ok)
        lanes_scene_free(out);
    return ok ? LANES_OK : err->status;
}

lanes_status lanes_scene_file_load(const char *path, lanes_scene *out, lanes_error *err)
{
    lanes_scene_init(out);
    struct stat st;
    if (stat(path, &st) != 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %s", path,
                               errno == ENOENT ? "no such file" : strerror(errno));
    }
    if (S_ISDIR(st.st_mode)) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: is a directory, not a scene file", path);
    }
    /* fopen of a FIFO blocks until a writer comes: never, for a stray one. */
    if (!S_ISREG(st.st_mode)) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: not a regular file (a device, FIFO or socket)",
                               path);
    }
    if (st.st_size > (off_t)MAX_SCENE_FILE) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "%s: %lld bytes: larger than the %u bytes a scene file may have "
                               "(geometry belongs in mesh files)",
                               path, (long long)st.st_size, MAX_SCENE_FILE);
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: cannot open: %s", path, strerror(errno));
    }
    size_t cap = (size_t)st.st_size + 1, len = 0;
    char *text = malloc(cap);
    if (!text) {
        fclose(f);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    /* Read to the end rather than trusting st_size (a file being written). */
    for (;;) {
        size_t got = fread(text + len, 1, cap - len, f);
        len += got;
        if (len < cap)
            break;
        if (cap >= MAX_SCENE_FILE) {
            len = cap + 1;
            break;
        }
        char *p = realloc(text, cap * 2);
        if (!p)
            break;
        text = p;
        cap *= 2;
    }
    bool rerr = ferror(f) != 0;
    fclose(f);
    if (rerr || len > MAX_SCENE_FILE) {
        free(text);
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %s", path,
                               rerr ? "read error" : "file too large");
    }
    char dir[4096];
    const char *slash = strrchr(path, '/');
    if (slash) {
        size_t n = (size_t)(slash - path);
        if (n >= sizeof dir) {
            free(text);
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: path too long", path);
        }
        memcpy(dir, path, n);
        dir[n] = '\0';
        if (n == 0)
            strcpy(dir, "/");
    } else {
        strcpy(dir, ".");
    }
    lanes_status status = lanes_scene_file_parse(text, len, path, dir, out, err);
    free(text);
    return status;
}
