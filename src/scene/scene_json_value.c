/*
 * scene_json_value.c — what every section of the JSON scene file is read with: a key's line (the
 * search that scene_json.c describes), messages that name the file and the line, typed values and
 * paths resolved against the scene file's directory or the shared scenes folder.
 */
#include "scene/json_context.h"

#include "core/error_at.h"
#include "core/vecmath.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------------ */
/* positions and messages */

int ic_json_line_of(json_ctx *c, size_t off)
{
    if (off > c->len)
        off = c->len;
    if (c->line_no < 1) {
        c->line_off = 0;
        c->line_no = 1;
    }
    size_t lo = off < c->line_off ? off : c->line_off, hi = off < c->line_off ? c->line_off : off;
    int newlines = 0;
    for (const char *p = c->text + lo, *e = c->text + hi; (p = memchr(p, '\n', (size_t)(e - p))) != NULL; ++p)
        ++newlines;
    c->scanned += hi - lo;
    c->line_no += off < c->line_off ? -newlines : newlines;
    c->line_off = off;
    return c->line_no;
}

/* Appends code point u to out as UTF-8 (RFC 3629); the number of bytes. */
static size_t utf8_encode(unsigned long u, char *out)
{
    if (u < 0x80) {
        out[0] = (char)u;
        return 1;
    }
    if (u < 0x800) {
        out[0] = (char)(0xC0 | (u >> 6));
        out[1] = (char)(0x80 | (u & 0x3F));
        return 2;
    }
    if (u < 0x10000) {
        out[0] = (char)(0xE0 | (u >> 12));
        out[1] = (char)(0x80 | ((u >> 6) & 0x3F));
        out[2] = (char)(0x80 | (u & 0x3F));
        return 3;
    }
    out[0] = (char)(0xF0 | (u >> 18));
    out[1] = (char)(0x80 | ((u >> 12) & 0x3F));
    out[2] = (char)(0x80 | ((u >> 6) & 0x3F));
    out[3] = (char)(0x80 | (u & 0x3F));
    return 4;
}

/* The 4 hex digits at t (a \u escape), or -1. */
static long hex4(const char *t, size_t n)
{
    if (n < 4)
        return -1;
    long v = 0;
    for (int k = 0; k < 4; ++k) {
        char h = t[k];
        int d = h >= '0' && h <= '9' ? h - '0' : h >= 'a' && h <= 'f' ? h - 'a' + 10 : h >= 'A' && h <= 'F' ? h - 'A' + 10 : -1;
        if (d < 0)
            return -1;
        v = 16 * v + d;
    }
    return v;
}

/* If the JSON string token opening at text[i] (a '"') decodes to exactly key (escapes included, RFC 8259
 * §7: "\u0074ype" is the key "type", as cJSON reads it), the offset just past its closing quote, else
 * 0. Reads no further than key's length allows. */
static size_t match_string(const json_ctx *c, size_t i, const char *key, size_t klen)
{
    const char *t = c->text;
    size_t j = i + 1, k = 0;
    while (j < c->len) {
        char ch = t[j];
        if (ch == '"')
            return k == klen ? j + 1 : 0;
        char buf[8];
        size_t n = 1;
        if (ch != '\\') {
            buf[0] = ch;
            ++j;
        } else if (j + 1 < c->len) {
            char e = t[j + 1];
            j += 2;
            switch (e) {
            case '"': case '\\': case '/': buf[0] = e; break;
            case 'b': buf[0] = '\b'; break;
            case 'f': buf[0] = '\f'; break;
            case 'n': buf[0] = '\n'; break;
            case 'r': buf[0] = '\r'; break;
            case 't': buf[0] = '\t'; break;
            case 'u': {
                long u = hex4(t + j, c->len - j);
                if (u < 0)
                    return 0;
                j += 4;
                if (u >= 0xD800 && u <= 0xDBFF && j + 6 <= c->len && t[j] == '\\' && t[j + 1] == 'u') {
                    long lo = hex4(t + j + 2, c->len - j - 2);
                    if (lo >= 0xDC00 && lo <= 0xDFFF) {
                        u = 0x10000 + ((u - 0xD800) << 10) + (lo - 0xDC00);
                        j += 6;
                    }
                }
                n = utf8_encode((unsigned long)u, buf);
                break;
            }
            default: return 0;
            }
        } else {
            return 0;
        }
        if (k + n > klen || memcmp(buf, key + k, n) != 0)
            return 0;
        k += n;
    }
    return 0;
}

/* Offset just past the next `"key"` followed by ':' at or after `from`, or (size_t)-1. */
static size_t find_key(json_ctx *c, const char *key, size_t from)
{
    size_t klen = strlen(key);
    for (size_t i = from; i < c->len; ++i) {
        const char *q = memchr(c->text + i, '"', c->len - i);
        if (!q)
            break;
        i = (size_t)(q - c->text);
        size_t j = match_string(c, i, key, klen);
        if (!j)
            continue;
        while (j < c->len && (c->text[j] == ' ' || c->text[j] == '\t' || c->text[j] == '\n' || c->text[j] == '\r'))
            ++j;
        if (j < c->len && c->text[j] == ':') {
            c->scanned += j + 1 - from;
            return j + 1;
        }
    }
    c->scanned += c->len - from;
    return (size_t)-1;
}

/* Moves the cursor past the next occurrence of key and returns its line (the last line if absent). */
int ic_json_locate_key(json_ctx *c, const char *key)
{
    size_t at = find_key(c, key, c->cursor);
    if (at != (size_t)-1) {
        c->line = ic_json_line_of(c, at);
        c->cursor = at;
    }
    return c->line;
}

/* Line of the next occurrence of key without moving the cursor. */
int ic_json_peek_key_line(json_ctx *c, const char *key)
{
    size_t at = find_key(c, key, c->cursor);
    return at != (size_t)-1 ? ic_json_line_of(c, at) : c->line;
}

/* Moves the cursor to the next '{' (the start of an array's object element) and returns its line. */
int ic_json_locate_object_start(json_ctx *c)
{
    const char *brace = memchr(c->text + c->cursor, '{', c->len - c->cursor);
    if (brace) {
        c->cursor = (size_t)(brace - c->text) + 1;
        c->line = ic_json_line_of(c, c->cursor);
    }
    return c->line;
}

ic_result ic_json_fail(json_ctx *c, int line, ic_result code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ic_result r = ic_error_vset_at(c->err, code, c->path, line, fmt, ap);
    va_end(ap);
    return r;
}

ic_result ic_json_unknown_key(json_ctx *c, int line, const char *key, const char *where, const char *valid)
{
    return ic_json_fail(c, line, IC_ERR_PARSE, "unknown key '%s' in %s; valid keys: %s", key, where, valid);
}

/* ------------------------------------------------------------------------------------------------ */
/* values */

static ic_result read_number(json_ctx *c, const cJSON *it, int line, double *out)
{
    if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble))
        return ic_json_fail(c, line, IC_ERR_PARSE, "'%s' must be a number", it->string);
    *out = it->valuedouble;
    return IC_OK;
}

ic_result ic_json_read_float(json_ctx *c, const cJSON *it, int line, float *out)
{
    double d = 0.0;
    ic_result r = read_number(c, it, line, &d);
    if (r == IC_OK && fabs(d) > 3.0e38)
        return ic_json_fail(c, line, IC_ERR_PARSE, "'%s' = %g is out of range", it->string, d);
    *out = (float)d;
    return r;
}

/* An integer in [lo, hi]. */
ic_result ic_json_read_int(json_ctx *c, const cJSON *it, int line, double lo, double hi, const char *hint, double *out)
{
    if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble) || it->valuedouble != floor(it->valuedouble) ||
        it->valuedouble < lo || it->valuedouble > hi) {
        char shown[64];
        if (cJSON_IsNumber(it))
            snprintf(shown, sizeof shown, "%g", it->valuedouble);
        else
            snprintf(shown, sizeof shown, "a non-number");
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "'%s' is %s but must be an integer from %.0f to %.0f; %s",
                            it->string, shown, lo, hi, hint);
    }
    *out = it->valuedouble;
    return IC_OK;
}

ic_result ic_json_read_vec3(json_ctx *c, const cJSON *it, int line, ic_vec3 *out)
{
    float v[3];
    /* An array's element has no key: it is then named by its place (its caller says which array). */
    char what[200];
    if (it && it->string)
        snprintf(what, sizeof what, "'%.180s'", it->string);
    else
        snprintf(what, sizeof what, "an array element");
    if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 3)
        return ic_json_fail(c, line, IC_ERR_PARSE, "%s must be an array of 3 numbers, like [0, 1, 0]", what);
    for (int k = 0; k < 3; ++k) {
        const cJSON *e = cJSON_GetArrayItem(it, k);
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble) || fabs(e->valuedouble) > 3.0e38)
            return ic_json_fail(c, line, IC_ERR_PARSE, "%s must be an array of 3 finite numbers, like [0, 1, 0]",
                                what);
        v[k] = (float)e->valuedouble;
    }
    *out = v3(v[0], v[1], v[2]);
    return IC_OK;
}

/* A colour: one non-negative number (grey) or [r, g, b]. */
ic_result ic_json_read_color(json_ctx *c, const cJSON *it, int line, ic_vec3 *out)
{
    ic_result r;
    if (cJSON_IsNumber(it)) {
        float g;
        r = ic_json_read_float(c, it, line, &g);
        *out = v3s(g);
    } else {
        r = ic_json_read_vec3(c, it, line, out);
    }
    if (r != IC_OK)
        return ic_json_fail(c, line, IC_ERR_PARSE, "'%s' must be a colour: a number or [r, g, b]", it->string);
    if (out->x < 0.0f || out->y < 0.0f || out->z < 0.0f)
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "'%s' has a negative component; colours must be >= 0",
                            it->string);
    return IC_OK;
}

ic_result ic_json_read_radiance(json_ctx *c, const cJSON *it, int line, ic_vec3 *out)
{
    ic_result r = ic_json_read_color(c, it, line, out);
    if (r == IC_OK && ic_radiance_too_large(*out))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "'%s' is " IC_RADIANCE_LIMIT_FMT "; " IC_RADIANCE_LIMIT_FIX,
                            it->string, IC_RADIANCE_LIMIT_ARGS(*out));
    return r;
}

ic_result ic_json_read_string(json_ctx *c, const cJSON *it, int line, const char **out)
{
    if (!cJSON_IsString(it) || !it->valuestring)
        return ic_json_fail(c, line, IC_ERR_PARSE, "'%s' must be a string", it->string);
    *out = it->valuestring;
    return IC_OK;
}

ic_result ic_json_expect_object(json_ctx *c, const cJSON *it, int line)
{
    if (!cJSON_IsObject(it))
        return ic_json_fail(c, line, IC_ERR_PARSE, "'%s' must be an object { ... }", it->string);
    return IC_OK;
}

/* ------------------------------------------------------------------------------------------------ */
/* paths */

/* The shared scenes folders in the order "shared:" paths try them: the option, $IRRCACHE_SCENES,
 * <dir>/../../../shared/scenes, <dir>/../../shared/scenes (entries may be NULL). */
static void shared_dirs(const json_ctx *c, char up3[IC_SCENE_PATH_MAX + 32], char up2[IC_SCENE_PATH_MAX + 32],
                        const char *dirs[4])
{
    snprintf(up3, IC_SCENE_PATH_MAX + 32, "%s/../../../shared/scenes", c->dir);
    snprintf(up2, IC_SCENE_PATH_MAX + 32, "%s/../../shared/scenes", c->dir);
    const char *env = getenv("IRRCACHE_SCENES");
    dirs[0] = c->opt->shared_scenes_dir;
    dirs[1] = (env && *env) ? env : NULL;
    dirs[2] = up3;
    dirs[3] = up2;
}

void ic_json_add_shared_roots(json_ctx *c)
{
    char up3[IC_SCENE_PATH_MAX + 32], up2[IC_SCENE_PATH_MAX + 32];
    const char *dirs[4];
    shared_dirs(c, up3, up2, dirs);
    for (int k = 0; k < 4; ++k)
        ic_scene_add_root(c->b, dirs[k]);
}

/* The file at `full` (resolved from `given`) may be read: inside the scene's folder tree or a shared
 * scenes folder, after symbolic links, unless allow_outside_paths (docs/scene-format.md, "Paths"). */
static ic_result check_inside(json_ctx *c, const char *given, int line, const char *what, const char *full)
{
    char where[IC_SCENE_PATH_MAX + 32], desc[IC_SCENE_PATH_MAX + 64];
    snprintf(where, sizeof where, "%s:%d", c->path, line);
    snprintf(desc, sizeof desc, "%s '%s'", what, given);
    return ic_scene_check_path(c->b, full, where, desc, c->err);
}

/* Resolves a path from the scene file: relative to its directory, or "shared:rest" against the shared
 * scenes folder (option, $IRRCACHE_SCENES, <dir>/../../../shared/scenes, <dir>/../../shared/scenes —
 * the first that holds the file). Reports `what` not found at line, or outside the folders the scene
 * may read from. */
ic_result ic_json_resolve_path(json_ctx *c, const char *given, int line, const char *what, char *out, size_t size)
{
    char tried[IC_SCENE_PATH_MAX] = "";
    if (!given[0])
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "empty path for %s; give a file name", what);
    if (!strncmp(given, "shared:", 7)) {
        const char *rest = given + 7;
        char up3[IC_SCENE_PATH_MAX + 32], up2[IC_SCENE_PATH_MAX + 32];
        const char *dirs[4];
        shared_dirs(c, up3, up2, dirs);
        for (int k = 0; k < 4; ++k) {
            if (!dirs[k] || !dirs[k][0])
                continue;
            if (!ic_path_join(dirs[k], rest, out, size))
                return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "path of %s '%s' is too long; shorten it", what,
                                    given);
            if (ic_path_exists(out))
                return check_inside(c, given, line, what, out);
            if (!tried[0])
                snprintf(tried, sizeof tried, "%s", out);
        }
        char abs_path[IC_SCENE_PATH_MAX];
        ic_path_absolute(tried, abs_path, sizeof abs_path);
        return ic_json_fail(c, line, IC_ERR_IO,
                            "%s '%s' not found (resolved to %s); check the path, or point $IRRCACHE_SCENES or the "
                            "shared_scenes_dir option at the shared scenes folder",
                            what, given, abs_path);
    }
    if (!ic_path_join(c->dir, given, out, size))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "path of %s '%s' is too long; shorten it", what, given);
    if (!ic_path_exists(out)) {
        char abs_path[IC_SCENE_PATH_MAX];
        ic_path_absolute(out, abs_path, sizeof abs_path);
        return ic_json_fail(c, line, IC_ERR_IO, "%s '%s' %s (resolved to %s); check the path", what, given,
                            ic_path_missing(out), abs_path);
    }
    return check_inside(c, given, line, what, out);
}
