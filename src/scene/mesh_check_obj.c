/*
 * mesh_check_obj.c — an OBJ file's vertices and faces, and its MTL files' colours, checked before assimp
 * imports them (the OBJ and MTL formats as Wavefront's Advanced Visualizer manual documents them).
 *
 * Lines are split as assimp 5.2 splits them (at \n, \r\n, \r, \f and NUL; a backslash at the end of a
 * line joins the next one), and a keyword counts only in the first column, as there, so that the vertices
 * counted here are the ones assimp reads. Then:
 * - a vertex line holds 3 (x y z), 4 (x y z w) or 6 (x y z r g b) numbers, all finite: assimp skips a
 *   line of another count without a word, and keeps NaN and infinity but renumbers vertices, so the
 *   first bad one is reported here with its line and its number as the file counts them;
 * - a texture coordinate (vt) or normal (vn) line holds numbers, all finite: assimp keeps a NaN normal (NaN
 *   shading samples, which the film drops: black pixels), and a NaN texture coordinate looks a texture up
 *   nowhere (the import used to read it as 0 without a word);
 * - every vertex index of a face, line or point names a vertex (1 to N, or -1 to -n for the n read so
 *   far): for an index past the end assimp throws "vertex index out of range" while it holds the meshes
 *   it has built, which leak (found by the mesh_obj fuzz target: a `mtllib` line without its line end
 *   swallowed the first vertex, and the second material's face named vertex 4 of 3). assimp takes every
 *   line whose first letter is f, l or p for a face, line or point, whatever follows the letter ("f3 4"
 *   is a face naming vertex 4: also found by the fuzzer), so these are checked the same way;
 * - a line element (l) names at least two vertices: for a line of one, assimp sizes the mesh's vertex
 *   array as for none and throws ("no vertices" or "bad vertex index"), leaking the meshes built before it
 *   (found by the fuzzer: `o r` then `l 4`).
 */
#include "scene/mesh_check.h"
#include "scene/scene_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

enum { OBJ_MAX_LINE = 1 << 16, OBJ_CHUNK = 1 << 16 };

/* The file read a chunk at a time, its lines scanned in memory. */
typedef struct obj_reader {
    FILE *fp;
    unsigned char *chunk;
    size_t len, pos;
} obj_reader;

/* 1 if a byte is left to read (reading the next chunk when the last is used up). */
static int reader_more(obj_reader *r)
{
    if (r->pos < r->len)
        return 1;
    r->len = fread(r->chunk, 1, OBJ_CHUNK, r->fp);
    r->pos = 0;
    return r->len > 0;
}

/* The bytes that end a line for assimp. */
static const unsigned char OBJ_LINE_END[256] = {['\n'] = 1, ['\r'] = 1, ['\f'] = 1, [0] = 1};

/* Reads the next line as assimp sees it into buf (continuations joined); *line_no advances by the line
 * ends consumed. Returns 0 at the end of the file, -1 if the line is longer than the buffer. */
static int obj_line(obj_reader *rd, char *buf, long *line_no)
{
    size_t n = 0;
    int any = 0;
    while (reader_more(rd)) {
        any = 1;
        /* the bytes up to the line's end or the chunk's, copied at once */
        const unsigned char *from = rd->chunk + rd->pos, *end = rd->chunk + rd->len, *q = from;
        while (q < end && !OBJ_LINE_END[*q])
            ++q;
        size_t run = (size_t)(q - from);
        if (run > OBJ_MAX_LINE - 1 - n)
            return -1;
        memcpy(buf + n, from, run);
        n += run;
        rd->pos += run;
        if (q == end)
            continue;
        if (rd->chunk[rd->pos++] == '\r' && reader_more(rd) && rd->chunk[rd->pos] == '\n')
            ++rd->pos;
        ++*line_no;
        if (n > 0 && buf[n - 1] == '\\') { /* continued on the next line */
            --n;
            continue;
        }
        break;
    }
    buf[n] = '\0';
    return any;
}

/* The next word of *at, split at spaces and tabs as strtok_r(…, " \t") splits, ended in place; NULL when
 * none is left. */
static char *next_word(char **at)
{
    char *p = *at;
    while (*p == ' ' || *p == '\t')
        ++p;
    if (!*p) {
        *at = p;
        return NULL;
    }
    char *w = p;
    while (*p && *p != ' ' && *p != '\t')
        ++p;
    if (*p)
        *p++ = '\0';
    *at = p;
    return w;
}

/* A component of a v, vt or vn line: [+-] digits with an optional fraction, or [+-] a fraction alone (".5"),
 * then an optional exponent; or nan / inf. assimp reads each of these, but counts the components of a v or vt
 * line by their first character, a digit or a sign, so an unsigned ".5" there counts for none (and the line
 * is skipped or read wrong): it is a number only where `bare_fraction` (a vn line, whose three words assimp
 * reads without counting them). *finite gets whether the value is finite as a float: decided from the digits
 * where the value is certainly below 10^38 (FLT_MAX is 3.4e38), else by converting it. */
static int obj_number(const char *w, int bare_fraction, int *finite)
{
    const char *c = w;
    if (*c == '+' || *c == '-')
        ++c;
    if (!strcasecmp(c, "nan") || !strcasecmp(c, "inf")) {
        *finite = 0;
        return 1;
    }
    if (!isdigit((unsigned char)*c) && !(*c == '.' && isdigit((unsigned char)c[1]) && (c > w || bare_fraction)))
        return 0;
    while (*c == '0')
        ++c;
    long magnitude = 0; /* the value is below 10^(magnitude + exponent) */
    for (; isdigit((unsigned char)*c); ++c)
        ++magnitude;
    if (*c == '.')
        for (++c; isdigit((unsigned char)*c);)
            ++c;
    long exponent = 0;
    if (*c == 'e' || *c == 'E') {
        ++c;
        int negative = *c == '-';
        if (*c == '+' || *c == '-')
            ++c;
        if (!isdigit((unsigned char)*c))
            return 0;
        for (; isdigit((unsigned char)*c); ++c)
            if (exponent < 100000)
                exponent = 10 * exponent + (*c - '0');
        if (negative)
            exponent = -exponent;
    }
    if (*c)
        return 0;
    *finite = magnitude + exponent <= 38 || isfinite((float)strtod(w, NULL));
    return 1;
}

/* An index of a face word: [-] digits (empty: *present = 0, allowed for the texture and normal parts). */
static int obj_index(const char *w, size_t len, long long *v, int *present)
{
    *present = len > 0;
    if (!len)
        return 1;
    size_t i = w[0] == '-';
    if (i == len)
        return 0;
    long long x = 0;
    for (; i < len; ++i) {
        if (!isdigit((unsigned char)w[i]) || x > 1000000000000LL)
            return 0;
        x = 10 * x + (w[i] - '0');
    }
    *v = w[0] == '-' ? -x : x;
    return 1;
}

/* The first face index past the end: checked once the vertices are counted. */
typedef struct obj_far_index {
    long long index;
    long line;
} obj_far_index;

/* The three kinds a face word indexes: positions (v), texture coordinates (vt) and normals (vn). */
static const char *const OBJ_KIND[3] = {"vertex", "texture coordinate (vt)", "normal (vn)"};

/* A v (kind 0), vt (1) or vn (2) line: every word a number, the components that give a position, a texture
 * coordinate or a normal finite (a vertex's w or colour aside). `number` is the element's as the file counts
 * its kind. */
static ic_result check_vector_line(int kind, char *c, const char *path, long line_no, long long number,
                                   ic_error *err)
{
    int count = 0, bad = 0;
    for (char *w = next_word(&c); w; w = next_word(&c)) {
        if (w[0] == '#')
            break; /* a comment ends the line */
        int finite;
        if (!obj_number(w, kind == 2, &finite))
            return ic_error_set(err, IC_ERR_PARSE, "%s:%ld: %s %lld: '%.40s' is not a number%s; fix the line or "
                                "export the mesh again", path, line_no, OBJ_KIND[kind], number, w,
                                w[0] == '.' ? " the importer reads here (write a 0 before the point)" : "");
        if ((kind > 0 || count < 3) && !finite)
            bad = 1;
        ++count;
    }
    if (kind == 0 && count != 3 && count != 4 && count != 6)
        return ic_error_set(err, IC_ERR_PARSE, "%s:%ld: vertex %lld has %d numbers; a vertex line holds 3 (x y z), 4 "
                            "(x y z w) or 6 (x y z r g b): fix the line or export the mesh again", path, line_no,
                            number, count);
    if (bad)
        return ic_error_set(err, IC_ERR_PARSE, "%s:%ld: %s %lld has a non-finite %s; fix or remove it", path, line_no,
                            OBJ_KIND[kind], number, kind == 0 ? "coordinate" : "component");
    return IC_OK;
}

static ic_result check_face_line(char kind, char *c, const char *path, long line_no, const long long so_far[3],
                                 obj_far_index far[3], ic_error *err)
{
    int references = 0;
    for (char *w = next_word(&c); w; w = next_word(&c), ++references) {
        /* v, v/vt, v//vn or v/vt/vn */
        long long idx[3] = {0, 0, 0};
        int present[3] = {0, 0, 0}, parts = 0, ok = 1;
        for (const char *p = w; ok; ++parts) {
            size_t len = 0;
            while (p[len] && p[len] != '/')
                ++len;
            ok = parts < 3 && obj_index(p, len, &idx[parts], &present[parts]);
            if (!p[len])
                break;
            p += len + 1;
        }
        if (!ok || !present[0] || (present[1] && idx[1] == 0) || (present[2] && idx[2] == 0) || idx[0] == 0)
            return ic_error_set(err, IC_ERR_PARSE, "%s:%ld: '%.40s' is not a vertex reference (v, v/vt, v//vn or "
                                "v/vt/vn, counted from 1, or from -1 backwards); fix the line or export the mesh again",
                                path, line_no, w);
        /* Texture and normal indices too: assimp dropped every normal or coordinate of the mesh for one past
         * the end, without a word. */
        for (int k = 0; k < 3; ++k) {
            if (!present[k])
                continue;
            if (idx[k] < 0 && -idx[k] > so_far[k])
                return ic_error_set(err, IC_ERR_PARSE, "%s:%ld: %s index %lld reaches before the first one (%lld "
                                    "read so far); fix the face or export the mesh again", path, line_no, OBJ_KIND[k],
                                    idx[k], so_far[k]);
            if (idx[k] > far[k].index) {
                far[k].index = idx[k];
                far[k].line = line_no;
            }
        }
    }
    if (kind == 'l' && references == 1)
        return ic_error_set(err, IC_ERR_PARSE, "%s:%ld: a line element (l) names one vertex; a line joins at least "
                            "two: fix or remove the line", path, line_no);
    return IC_OK;
}

ic_result ic_obj_check(FILE *fp, const char *path, unsigned long long max_elements, ic_error *err)
{
    char *line = malloc(OBJ_MAX_LINE);
    obj_reader rd = {fp, malloc(OBJ_CHUNK), 0, 0};
    if (!line || !rd.chunk) {
        free(line);
        free(rd.chunk);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory", path);
    }
    long line_no = 0;
    long long vertices = 0, faces = 0, counts[3] = {0, 0, 0};
    obj_far_index far[3] = {{0, 0}, {0, 0}, {0, 0}};
    ic_result r = IC_OK;
    for (;;) {
        long at = line_no + 1; /* the line this one starts on */
        int got = obj_line(&rd, line, &line_no);
        if (got == 0)
            break;
        if (got < 0) {
            r = ic_error_set(err, IC_ERR_PARSE, "%s:%ld: a line longer than %d bytes; the file is corrupt: export "
                             "the mesh again", path, at, OBJ_MAX_LINE - 1);
            break;
        }
        if (line[0] == 'v' && (line[1] == ' ' || line[1] == '\t'))
            r = check_vector_line(0, line + 2, path, at, ++vertices, err);
        else if (line[0] == 'v' && (line[1] == 't' || line[1] == 'n') && (line[2] == ' ' || line[2] == '\t')) {
            int kind = line[1] == 't' ? 1 : 2;
            r = check_vector_line(kind, line + 3, path, at, ++counts[kind], err);
        }
        else if (line[0] == 'f' || line[0] == 'l' || line[0] == 'p') {
            /* assimp reads any line that starts with one of these letters as a face, line or point, its
             * first word ("f", or "f3", "fo") skipped */
            counts[0] = vertices;
            r = check_face_line(line[0], line + strcspn(line, " \t"), path, at, counts, far, err);
        }
        if (r == IC_OK && line[0] == 'f')
            ++faces;
        if (r == IC_OK && ((unsigned long long)vertices > max_elements || (unsigned long long)faces > max_elements))
            r = ic_error_set(err, IC_ERR_UNSUPPORTED, "%s:%ld: more than %llu %s, the limit; raise it with "
                             "--max-mesh-elements (max_mesh_elements of ic_scene_load_options) if the mesh is really "
                             "this large", path, at, max_elements, faces > (long long)max_elements ? "faces" : "vertices");
        if (r != IC_OK)
            break;
    }
    counts[0] = vertices;
    for (int k = 0; r == IC_OK && k < 3; ++k)
        if (far[k].index > counts[k])
            r = ic_error_set(err, IC_ERR_PARSE, "%s:%ld: a face names %s %lld, but the file has %lld; fix the face or "
                             "export the mesh again", path, far[k].line, OBJ_KIND[k], far[k].index, counts[k]);
    free(line);
    free(rd.chunk);
    return r;
}

int ic_bad_color_component(float v)
{
    return !(v >= 0.0f) || !isfinite(v);
}

/* The warning for a texture line c (`map_Kd -s 2 2 1 wood.png`) of an MTL file whose options the import would
 * not apply (ic_mtl_check), or none. */
static void warn_map_options(ic_scene *s, const char *mtl_path, long line_no, const char *material, const char *c)
{
    size_t key_len = strcspn(c, " \t\r\n");
    if (!s || (strncmp(c, "map_", 4) && strncmp(c, "norm", 4) && strncmp(c, "bump", 4) && strncmp(c, "disp", 4)))
        return;
    char unapplied[64] = ""; /* the options given other than their defaults, "-s -clamp" */
    for (const char *v = c + key_len; *v && *v != '\r' && *v != '\n';) {
        while (*v == ' ' || *v == '\t')
            ++v;
        size_t n = strcspn(v, " \t\r\n");
        int is_uvw = n == 2 && v[0] == '-' && (v[1] == 's' || v[1] == 'o' || v[1] == 't');
        int is_clamp = n == 6 && !strncmp(v, "-clamp", 6);
        const char *w = v + n;
        int differs = 0;
        if (is_clamp) { /* -clamp on|off */
            while (*w == ' ' || *w == '\t')
                ++w;
            differs = !strncmp(w, "on", 2);
        }
        for (int k = 0; is_uvw && k < 3; ++k) { /* -s u [v [w]] (default 1), -o and -t u [v [w]] (default 0) */
            char *end;
            float f = strtof(w, &end);
            if (end == w)
                break;
            differs |= f != (v[1] == 's' ? 1.0f : 0.0f);
            w = end;
        }
        size_t used = strlen(unapplied);
        if (differs)
            snprintf(unapplied + used, sizeof unapplied - used, "%s%.*s", used ? " " : "", (int)n, v);
        v += n;
    }
    if (unapplied[0])
        ic_scene_warn(s, "%s:%ld: material '%s': the texture options %s of %.*s are not applied: the OBJ's texture "
                      "coordinates are used as they are, and textures repeat beyond [0, 1]; scale or offset the vt "
                      "coordinates instead (and keep them within [0, 1] for a clamped texture)",
                      mtl_path, line_no, material, unapplied, (int)key_len, c);
}

ic_result ic_mtl_check(const char *mtl_path, ic_scene *s, ic_error *err)
{
    FILE *fp = fopen(mtl_path, "rb");
    if (!fp)
        return IC_OK; /* assimp warns and the materials take their defaults */
    char line[4096], material[128] = "";
    long line_no = 0;
    ic_result r = IC_OK;
    while (r == IC_OK && fgets(line, sizeof line, fp)) {
        ++line_no;
        const char *c = line;
        while (*c == ' ' || *c == '\t')
            ++c;
        if (!strncmp(c, "newmtl", 6) && (c[6] == ' ' || c[6] == '\t')) {
            c += 7;
            while (*c == ' ' || *c == '\t')
                ++c;
            snprintf(material, sizeof material, "%.*s", (int)strcspn(c, "\r\n"), c);
        } else if (c[0] == 'm' || c[0] == 'n' || c[0] == 'b' || c[0] == 'd') {
            warn_map_options(s, mtl_path, line_no, material, c);
        } else if (c[0] == 'K' && (c[1] == 'd' || c[1] == 's' || c[1] == 'e') && (c[2] == ' ' || c[2] == '\t')) {
            const char *what = c[1] == 'd' ? "Kd (diffuse)" : c[1] == 's' ? "Ks (specular)" : "Ke (emission)";
            const char *v = c + 3;
            for (int k = 0; k < 3; ++k) {
                char *end;
                float f = strtof(v, &end);
                if (end == v)
                    break; /* no more numbers ("spectral", "xyz" or the end of the line) */
                if (ic_bad_color_component(f)) {
                    r = ic_error_set(err, IC_ERR_PARSE,
                                     "%s:%ld: material '%s': %s has a negative or non-finite value (%.*s); give "
                                     "values >= 0",
                                     mtl_path, line_no, material, what, (int)strcspn(c + 3, "\r\n"), c + 3);
                    break;
                }
                if (c[1] == 'e' && ic_radiance_too_large(v3s(f))) {
                    r = ic_error_set(err, IC_ERR_INVALID_ARG,
                                     "%s:%ld: material '%s': %s is " IC_RADIANCE_LIMIT_FMT "; " IC_RADIANCE_LIMIT_FIX,
                                     mtl_path, line_no, material, what, (double)f, IC_SCENE_MAX_RADIANCE);
                    break;
                }
                v = end;
            }
        }
        while (!strchr(line, '\n') && fgets(line, sizeof line, fp)) { /* skip the rest of a long line */
        }
    }
    fclose(fp);
    return r;
}
