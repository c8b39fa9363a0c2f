/*
 * mesh_check_ply.c — a PLY file's structure checked before assimp imports it (Turk 1994; the format as
 * Paul Bourke documents it): the line "ply", a text header of elements (each with a count and typed
 * properties, a list property with its count type), "end_header", then every element's instances in
 * header order, one per line in ascii, packed in binary of either byte order.
 *
 * Why each check (assimp 5.2.5, found by the mesh_ply fuzz target, tests/fuzz/regress/mesh_ply/):
 * - the first line must be exactly "ply": assimp takes "ply&" or "ply\0" as PLY too, so such files got
 *   past a check that looked only for "ply\n";
 * - the header must end with end_header and hold only its six kinds of line: without end_header
 *   assimp's header parser loops for ever at the end of the file, or reads past its buffer when an
 *   element line holds a NUL byte (SEGV);
 * - every value the header declares must be there: on a truncated binary body assimp reads its buffer's
 *   padding as data, so a face gets ten indices of 0x0a0a0a0a (SEGV in triangulation);
 * - face indices must name existing vertices: assimp's post-processing indexes the vertex array with
 *   them unchecked (SEGV in JoinIdenticalVertices);
 * - an ascii value must be a number of its property's type: assimp throws on a word where a number
 *   belongs and leaks the element it was filling.
 * - lines end with \n or \r\n: assimp also ends a line at a lone \r, so "pro\rperty float y" declared a
 *   property for us and none for it, and the binary records it read were shorter (SEGV); it also skips one
 *   \n after end_header's line end, even as the first byte of binary data, and the check skips it too;
 * - an element it does not know by name must come after the ones with instances (ply_known_element);
 * - a face's texcoord list of 6 to 8 values (assimp reads no other length) is read as a u v pair per vertex
 *   of the face, through the face's vertex indices unchecked: a face with fewer vertices than the pairs had
 *   its index array read past its end, and a face element with a texcoord list but no vertex index list
 *   gave faces without indices (a NULL read, or an assertion in triangulation), so a face needs as many
 *   vertices as the list has pairs (face_texcoords).
 * And, as before, every element count against the caller's limit (before the body is read), and every
 * vertex's x, y, z finite even where no face uses it (assimp drops such a vertex silently), and its normal
 * and texture coordinates finite (a NaN normal gives NaN shading samples, which the film drops: black
 * pixels; a NaN texture coordinate looks a texture up nowhere).
 */
#include "scene/mesh_check.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

enum {
    PLY_MAX_ELEMENTS = 16,
    PLY_MAX_PROPS = 32,
    PLY_MAX_HEADER_LINES = 4096,
    PLY_MAX_HEADER_LINE = 1024,
    PLY_MAX_FACE_VERTICES = 1024, /* one polygon of a face list: triangulated by assimp, quadratic in it */
    PLY_MAX_LIST = 1 << 16,       /* any other list property of one instance */
    PLY_MAX_ASCII_LINE = 1 << 16  /* one ascii instance: PLY_MAX_FACE_VERTICES indices fit many times over */
};

typedef struct ply_prop {
    char name[64];
    int size, is_float, is_signed;   /* the value, or each item of a list */
    int count_size, count_signed;    /* a list's count (count_size 0: a scalar property) */
    const char *attribute;           /* what assimp reads it as, which must be finite: "coordinate" (x, y, z of
                                      * the vertex element), "normal", "texture coordinate"; NULL: another */
    int is_index;                    /* a vertex index list (vertex_indices of face or tristrips) */
} ply_prop;

typedef struct ply_element {
    char name[64];
    unsigned long long count;
    ply_prop props[PLY_MAX_PROPS];
    int prop_count;
} ply_element;

typedef struct ply_file {
    FILE *fp;
    const char *path;
    ic_error *err;
    int format;                      /* 0 ascii, 1 binary little-endian, 2 binary big-endian */
    int crlf;                        /* the header line just read ended with \r\n (else \n or the end) */
    long line;                       /* the line just read (header, or an ascii instance) */
    ply_element el[PLY_MAX_ELEMENTS];
    int el_count;
    unsigned long long vertices;     /* the vertex element's count: the range of face indices */
    double indices, texcoords;       /* the instance's vertex index and face texcoord list lengths (-1: none) */
    char *text;                      /* an ascii instance line (PLY_MAX_ASCII_LINE bytes) */
} ply_file;

/* Bytes of a PLY scalar type (both spellings: "float" and "float32"), 0 if unknown. */
static int ply_type(const char *t, int *is_float, int *is_signed)
{
    static const struct { const char *name; int size, is_float, is_signed; } types[] = {
        {"char", 1, 0, 1},   {"int8", 1, 0, 1},    {"uchar", 1, 0, 0},  {"uint8", 1, 0, 0},    {"short", 2, 0, 1},
        {"int16", 2, 0, 1},  {"ushort", 2, 0, 0},  {"uint16", 2, 0, 0}, {"int", 4, 0, 1},      {"int32", 4, 0, 1},
        {"uint", 4, 0, 0},   {"uint32", 4, 0, 0},  {"float", 4, 1, 1},  {"float32", 4, 1, 1}, {"double", 8, 1, 1},
        {"float64", 8, 1, 1}};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; ++i)
        if (!strcmp(t, types[i].name)) {
            *is_float = types[i].is_float;
            *is_signed = types[i].is_signed;
            return types[i].size;
        }
    return 0;
}

/* A binary value of `size` bytes at p, in the file's byte order, as a double. */
static double ply_value(const unsigned char *p, int size, int is_float, int is_signed, int big_endian)
{
    uint64_t u = 0;
    for (int i = 0; i < size; ++i)
        u |= (uint64_t)p[big_endian ? size - 1 - i : i] << (8 * i);
    if (is_float && size == 4) {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, sizeof f);
        return f;
    }
    if (is_float) {
        double d;
        memcpy(&d, &u, sizeof d);
        return d;
    }
    if (is_signed && size < 8 && (u >> (8 * size - 1)) & 1u)
        return (double)(int64_t)(u | ~(uint64_t)0 << (8 * size));
    return (double)u;
}

/* The elements assimp 5.2 knows by name. For any other it takes the element's count from the start of its
 * name (0, or the digits a name begins with), so it skips none of its instances and reads them as the next
 * element's (found by the mesh_ply fuzz target: a custom element before the faces gave faces of garbage
 * indices, SEGV in post-processing; a name of a hundred digits, a 34 GB allocation). */
static int ply_known_element(const char *name)
{
    static const char *const known[] = {"vertex", "face", "tristrips", "edge", "material"};
    for (size_t i = 0; i < sizeof known / sizeof known[0]; ++i)
        if (!strcmp(name, known[i]))
            return 1;
    return 0;
}

/* What assimp 5.2 reads property `name` of element `element` as, for the values that must be finite: a
 * vertex's position (x, y, z), normal (nx, ny, nz) or texture coordinate (u, v, or s, t as Blender writes
 * them, tx, ty, texture_u, texture_v), and a face's texture coordinates (its list "texcoord"). NULL for
 * any other property. */
static const char *ply_attribute(const char *element, const char *name, int is_list)
{
    static const char *const normal[] = {"nx", "ny", "nz"};
    static const char *const uv[] = {"u", "v", "s", "t", "tx", "ty", "texture_u", "texture_v"};
    if (!strcmp(element, "face"))
        return is_list && !strcmp(name, "texcoord") ? "texture coordinate" : NULL;
    if (strcmp(element, "vertex") || is_list)
        return NULL;
    if (name[0] >= 'x' && name[0] <= 'z' && !name[1])
        return "coordinate";
    for (size_t i = 0; i < sizeof normal / sizeof normal[0]; ++i)
        if (!strcmp(name, normal[i]))
            return "normal";
    for (size_t i = 0; i < sizeof uv / sizeof uv[0]; ++i)
        if (!strcmp(name, uv[i]))
            return "texture coordinate";
    return NULL;
}

/* Reads one header line into line (without its line end). Returns 1, 0 at the end of the file, or -1 with
 * the error set (too long, or a control byte: no exporter writes one, and assimp's parser trips on NUL). */
static int header_line(ply_file *f, char *line)
{
    int n = 0, c;
    f->crlf = 0;
    while ((c = getc(f->fp)) != EOF && c != '\n') {
        if (c == '\r') {
            int d = getc(f->fp);
            if (d == '\n') {
                f->crlf = 1;
                break;
            }
            ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: a carriage return inside a PLY header line (assimp ends the "
                         "line there); end lines with \\n or \\r\\n: export the mesh again", f->path, f->line);
            return -1;
        }
        if ((c < 0x20 && c != '\t') || c == 0x7f) {
            ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: the PLY header holds the byte 0x%02x, which is not text; "
                         "the file is corrupt: export the mesh again", f->path, f->line, c);
            return -1;
        }
        if (n == PLY_MAX_HEADER_LINE - 1) {
            ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: PLY header line longer than %d bytes; fix the header or "
                         "export the mesh again", f->path, f->line, PLY_MAX_HEADER_LINE - 1);
            return -1;
        }
        line[n++] = (char)c;
    }
    line[n] = '\0';
    return c == EOF && n == 0 ? 0 : 1;
}

/* Splits line at spaces and tabs into at most max words; returns how many there are (all of them,
 * even beyond max). */
static int split_words(char *line, char **word, int max)
{
    int n = 0;
    for (char *c = line;;) {
        while (*c == ' ' || *c == '\t')
            ++c;
        if (!*c)
            return n;
        if (n < max)
            word[n] = c;
        ++n;
        while (*c && *c != ' ' && *c != '\t')
            ++c;
        if (*c)
            *c++ = '\0';
    }
}

static int header_error(ply_file *f, ic_result code, const char *what)
{
    ic_error_set(f->err, code, "%s:%ld: %s", f->path, f->line, what);
    return 0;
}

/* Reads the header after the "ply" line; the file is then at the first byte of the body. Returns 0 with
 * the error set. */
static int read_header(ply_file *f)
{
    char line[PLY_MAX_HEADER_LINE], *w[8];
    char msg[512];
    f->format = -1;
    for (f->line = 2; f->line <= PLY_MAX_HEADER_LINES; ++f->line) {
        int got = header_line(f, line);
        if (got < 0)
            return 0;
        if (got == 0)
            break;
        char shown[64];
        snprintf(shown, sizeof shown, "%.60s", line);
        int n = split_words(line, w, 8);
        if (n == 0)
            return header_error(f, IC_ERR_PARSE, "empty line in the PLY header; remove it");
        if (!strcmp(w[0], "comment") || !strcmp(w[0], "obj_info"))
            continue;
        if (!strcmp(w[0], "end_header")) {
            if (n != 1)
                return header_error(f, IC_ERR_PARSE, "text after 'end_header'; fix the header");
            if (f->format < 0)
                return header_error(f, IC_ERR_PARSE, "PLY header has no 'format' line; export the mesh again");
            if (f->format > 0 && !f->crlf) {
                /* assimp skips one \n after the line end of end_header (the \n of \r\n, or a blank line), even
                 * where it is the first byte of the binary data: check the data it reads */
                int c = getc(f->fp);
                if (c != '\n' && c != EOF)
                    ungetc(c, f->fp);
            }
            return 1;
        }
        if (!strcmp(w[0], "format")) {
            if (f->format >= 0 || f->el_count > 0)
                return header_error(f, IC_ERR_PARSE, "a 'format' line after the first, or after an element; fix "
                                    "the header");
            if (n != 3 || strcmp(w[2], "1.0"))
                return header_error(f, IC_ERR_PARSE, "the format line must read 'format ascii 1.0' (or "
                                    "binary_little_endian, binary_big_endian); fix the header");
            f->format = !strcmp(w[1], "ascii") ? 0 : !strcmp(w[1], "binary_little_endian") ? 1
                        : !strcmp(w[1], "binary_big_endian") ? 2 : -1;
            if (f->format < 0) {
                snprintf(msg, sizeof msg, "unknown PLY format '%.40s' (ascii, binary_little_endian or "
                         "binary_big_endian); fix the header", w[1]);
                return header_error(f, IC_ERR_PARSE, msg);
            }
        } else if (!strcmp(w[0], "element")) {
            if (n != 3)
                return header_error(f, IC_ERR_PARSE, "an element line is 'element NAME COUNT'; fix the header");
            if (f->el_count == PLY_MAX_ELEMENTS) {
                snprintf(msg, sizeof msg, "more than %d PLY elements; keep vertices and faces", PLY_MAX_ELEMENTS);
                return header_error(f, IC_ERR_UNSUPPORTED, msg);
            }
            for (int i = 0; i < f->el_count; ++i)
                if (!strcmp(f->el[i].name, w[1])) {
                    snprintf(msg, sizeof msg, "element '%.60s' declared twice; fix the header", w[1]);
                    return header_error(f, IC_ERR_PARSE, msg);
                }
            ply_element *e = &f->el[f->el_count++];
            memset(e, 0, sizeof *e);
            snprintf(e->name, sizeof e->name, "%s", w[1]);
            char *end;
            errno = 0;
            e->count = strtoull(w[2], &end, 10);
            if (*end || !isdigit((unsigned char)w[2][0]) || errno == ERANGE) {
                snprintf(msg, sizeof msg, "PLY element '%.60s' has count '%.40s', not a number; fix the header", w[1],
                         w[2]);
                return header_error(f, IC_ERR_PARSE, msg);
            }
        } else if (!strcmp(w[0], "property")) {
            if (f->el_count == 0)
                return header_error(f, IC_ERR_PARSE, "a property before any element; fix the header");
            ply_element *e = &f->el[f->el_count - 1];
            if (e->prop_count == PLY_MAX_PROPS) {
                snprintf(msg, sizeof msg, "more than %d properties in PLY element '%s'; drop the ones not needed",
                         PLY_MAX_PROPS, e->name);
                return header_error(f, IC_ERR_UNSUPPORTED, msg);
            }
            ply_prop *p = &e->props[e->prop_count++];
            memset(p, 0, sizeof *p);
            int is_list = n >= 2 && !strcmp(w[1], "list");
            if (n != (is_list ? 5 : 3))
                return header_error(f, IC_ERR_PARSE, "a property line is 'property TYPE NAME' or 'property list "
                                    "COUNT_TYPE TYPE NAME'; fix the header");
            snprintf(p->name, sizeof p->name, "%s", w[n - 1]);
            int count_float = 0;
            if (is_list && (p->count_size = ply_type(w[2], &count_float, &p->count_signed)) == 0)
                p->size = 0;
            else
                p->size = ply_type(w[n - 2], &p->is_float, &p->is_signed);
            if (!p->size) {
                snprintf(msg, sizeof msg, "unknown PLY property type in '%s' (char, uchar, short, ushort, int, "
                         "uint, float, double or their sized names); fix the header", shown);
                return header_error(f, IC_ERR_PARSE, msg);
            }
            if (count_float) {
                snprintf(msg, sizeof msg, "the count of list '%s' is of a floating-point type; give it an integer "
                         "type (uchar or int)", p->name);
                return header_error(f, IC_ERR_PARSE, msg);
            }
            /* a face's vertex_indices (or vertex_index) list; any list of a tristrips element, since assimp
             * reads a strip from its list whatever the list is called (found by the fuzzer: a strip list
             * named "vertex_indiceq" was not checked, and its indices past the vertices crashed assimp) */
            p->is_index = is_list && ((!strcmp(e->name, "face") && (!strcmp(p->name, "vertex_indices") ||
                                                                    !strcmp(p->name, "vertex_index"))) ||
                                      !strcmp(e->name, "tristrips"));
            if (p->is_index && p->is_float) {
                snprintf(msg, sizeof msg, "the vertex indices of '%s' are of a floating-point type; give them an "
                         "integer type (int or uint)", e->name);
                return header_error(f, IC_ERR_PARSE, msg);
            }
            p->attribute = ply_attribute(e->name, p->name, is_list);
        } else {
            snprintf(msg, sizeof msg, "'%s' is not a PLY header line (format, comment, obj_info, element, "
                     "property or end_header); fix the header or export the mesh again", shown);
            return header_error(f, IC_ERR_PARSE, msg);
        }
    }
    ic_error_set(f->err, IC_ERR_PARSE, "%s: PLY header without 'end_header' in its first %d lines; export the "
                 "mesh again", f->path, PLY_MAX_HEADER_LINES);
    return 0;
}

/* Where an instance is, for messages: "file:line" (ascii) or "file" (binary). */
static void where(const ply_file *f, char *out, size_t size)
{
    if (f->format == 0)
        snprintf(out, size, "%s:%ld", f->path, f->line);
    else
        snprintf(out, size, "%s", f->path);
}

static ic_result truncated(ply_file *f, const ply_element *e, unsigned long long i)
{
    return ic_error_set(f->err, IC_ERR_PARSE, "%s: the data ends in element '%s' %llu of %llu (%s), before what "
                        "the header declares; the file is truncated: export the mesh again", f->path, e->name, i + 1,
                        e->count, f->format == 0 ? "ascii" : "binary");
}

/* Checks one value of property p of instance i of e: a coordinate, normal or texture coordinate finite, a
 * list's count in range, a vertex index naming a vertex. `item` is -1 for a scalar or a list's count, else the
 * item's position. */
static ic_result check_value(ply_file *f, const ply_element *e, const ply_prop *p, unsigned long long i, long item,
                             double v)
{
    char at[4200];
    where(f, at, sizeof at);
    if (p->attribute && (item >= 0 || !p->count_size) && (!isfinite(v) || !isfinite((float)v)))
        return f->format == 0 ? ic_error_set(f->err, IC_ERR_PARSE, "%s: %s %llu has a non-finite %s (%g); fix or "
                                             "remove it", at, e->name, i + 1, p->attribute, v)
                              : ic_error_set(f->err, IC_ERR_PARSE, "%s: %s %llu (of %llu, binary) has a non-finite "
                                             "%s (%g); fix or remove it", at, e->name, i + 1, e->count, p->attribute,
                                             v);
    if (p->count_size && item < 0) {
        if (p->is_index)
            f->indices = v;
        else if (p->attribute) /* a list property with an attribute: the face's texcoord list */
            f->texcoords = v;
        long max = p->is_index ? PLY_MAX_FACE_VERTICES : PLY_MAX_LIST;
        if (v < (p->is_index ? 1 : 0) || v > max)
            return ic_error_set(f->err, IC_ERR_PARSE, "%s: %s %llu has a list '%s' of %.0f items, outside 0 to %ld "
                                "(faces: 1 to %d); fix it or export the mesh again (triangulated)", at, e->name,
                                i + 1, p->name, v, max, PLY_MAX_FACE_VERTICES);
    } else if (p->is_index) {
        int restart = !strcmp(e->name, "tristrips") && v == -1.0; /* a strip restart */
        if (!restart && !(v >= 0 && v < (double)f->vertices))
            return ic_error_set(f->err, IC_ERR_PARSE, "%s: %s %llu names vertex %.0f, but the file has %llu vertices "
                                "(0 to %llu); fix the %s or export the mesh again", at, e->name, i + 1, v,
                                f->vertices, f->vertices ? f->vertices - 1 : 0, e->name);
    }
    return IC_OK;
}

/* After instance i of e: a face texcoord list that assimp reads (6 to 8 values, a u v pair per vertex) needs
 * a vertex of the face for each pair, which it looks up by the face's vertex indices. */
static ic_result face_texcoords(ply_file *f, const ply_element *e, unsigned long long i)
{
    double pairs = ceil(f->texcoords / 2);
    if (!(f->texcoords >= 6 && f->texcoords <= 8) || f->indices >= pairs)
        return IC_OK;
    char at[4200];
    where(f, at, sizeof at);
    return ic_error_set(f->err, IC_ERR_PARSE, "%s: %s %llu%s has a list 'texcoord' of %.0f values (a u v pair for "
                        "each of %.0f vertices) but %.0f vertices; give each vertex its pair, or export the mesh "
                        "again", at, e->name, i + 1, f->format == 0 ? "" : " (binary)", f->texcoords, pairs,
                        f->indices < 0 ? 0.0 : f->indices);
}

/* One binary value of `size` bytes; 0 at the end of the file. */
static int binary_value(ply_file *f, int size, int is_float, int is_signed, double *v)
{
    unsigned char b[8];
    if (fread(b, 1, (size_t)size, f->fp) != (size_t)size)
        return 0;
    *v = ply_value(b, size, is_float, is_signed, f->format == 2);
    return 1;
}

static ic_result binary_instance(ply_file *f, const ply_element *e, unsigned long long i)
{
    f->indices = f->texcoords = -1;
    for (int k = 0; k < e->prop_count; ++k) {
        const ply_prop *p = &e->props[k];
        double v;
        ic_result r;
        if (!p->count_size) {
            if (!binary_value(f, p->size, p->is_float, p->is_signed, &v))
                return truncated(f, e, i);
            if ((r = check_value(f, e, p, i, -1, v)) != IC_OK)
                return r;
            continue;
        }
        if (!binary_value(f, p->count_size, 0, p->count_signed, &v))
            return truncated(f, e, i);
        if ((r = check_value(f, e, p, i, -1, v)) != IC_OK)
            return r;
        long items = (long)v;
        for (long j = 0; j < items; ++j) {
            if (!binary_value(f, p->size, p->is_float, p->is_signed, &v))
                return truncated(f, e, i);
            if ((r = check_value(f, e, p, i, j, v)) != IC_OK)
                return r;
        }
    }
    return face_texcoords(f, e, i);
}

/* 1 if word is a decimal number as assimp reads one: digits, signed for a signed or float type, and for a
 * float an optional fraction and exponent, or nan / inf. */
static int is_number(const char *w, int is_float, int is_signed)
{
    const char *c = w;
    if ((is_float || is_signed) && (*c == '+' || *c == '-')) /* assimp reads no sign before an unsigned value */
        ++c;
    if (is_float && (!strcasecmp(c, "nan") || !strcasecmp(c, "inf")))
        return 1;
    int digits = 0;
    while (isdigit((unsigned char)*c))
        ++c, ++digits;
    if (is_float && *c == '.') {
        ++c;
        while (isdigit((unsigned char)*c))
            ++c, ++digits;
    }
    if (!digits)
        return 0;
    if (is_float && (*c == 'e' || *c == 'E')) {
        ++c;
        if (*c == '+' || *c == '-')
            ++c;
        if (!isdigit((unsigned char)*c))
            return 0;
        while (isdigit((unsigned char)*c))
            ++c;
    }
    return *c == '\0';
}

/* The range of an integer type of `size` bytes. */
static int in_int_range(double v, int size, int is_signed)
{
    double span = ldexp(1.0, 8 * size);
    return is_signed ? v >= -span / 2 && v < span / 2 : v >= 0 && v < span;
}

/* The next word of an ascii instance as a value of the given type; the error names the property. */
static ic_result ascii_value(ply_file *f, const ply_element *e, const ply_prop *p, unsigned long long i,
                             char **cursor, int size, int is_float, int is_signed, double *v)
{
    char *c = *cursor;
    while (*c == ' ' || *c == '\t')
        ++c;
    char *w = c;
    while (*c && *c != ' ' && *c != '\t')
        ++c;
    if (c == w)
        return ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: %s %llu ends before its property '%s'; give every "
                            "property its value, one instance per line", f->path, f->line, e->name, i + 1, p->name);
    char saved = *c;
    *c = '\0';
    int ok = is_number(w, is_float, is_signed);
    *v = ok ? strtod(w, NULL) : 0.0;
    if (ok && !is_float && !in_int_range(*v, size, is_signed))
        ok = 0;
    if (!ok) {
        ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: '%.40s' is not %s (property '%s' of %s %llu); fix the value or "
                     "export the mesh again", f->path, f->line, w, is_float ? "a number" : "an integer of its type",
                     p->name, e->name, i + 1);
        *c = saved;
        return IC_ERR_PARSE;
    }
    *c = saved;
    *cursor = c;
    return IC_OK;
}

/* Reads the next ascii line into f->text; 0 at the end of the file, -1 with the error set. */
static int ascii_line(ply_file *f)
{
    int n = 0, c;
    ++f->line;
    while ((c = getc_unlocked(f->fp)) != EOF && c != '\n') {
        if (c == '\r') {
            int d = getc_unlocked(f->fp);
            if (d == '\n')
                break;
            if (d == EOF)
                continue;
            ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: a carriage return inside a line of ascii PLY data (assimp "
                         "ends the line there); end lines with \\n or \\r\\n: export the mesh again", f->path,
                         f->line);
            return -1;
        }
        if (c == '\0' || c == '\f' || c == '\v') {
            ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: the byte 0x%02x in ascii PLY data; the file is corrupt: "
                         "export the mesh again", f->path, f->line, c);
            return -1;
        }
        if (n == PLY_MAX_ASCII_LINE - 1) {
            ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: a line longer than %d bytes in ascii PLY data; export the "
                         "mesh as binary PLY", f->path, f->line, PLY_MAX_ASCII_LINE - 1);
            return -1;
        }
        f->text[n++] = (char)c;
    }
    f->text[n] = '\0';
    return c == EOF && n == 0 ? 0 : 1;
}

static ic_result ascii_instance(ply_file *f, const ply_element *e, unsigned long long i)
{
    int got = ascii_line(f);
    if (got < 0)
        return f->err ? f->err->code : IC_ERR_PARSE;
    if (got == 0)
        return truncated(f, e, i);
    char *c = f->text;
    ic_result r;
    f->indices = f->texcoords = -1;
    for (int k = 0; k < e->prop_count; ++k) {
        const ply_prop *p = &e->props[k];
        double v;
        if (!p->count_size) {
            if ((r = ascii_value(f, e, p, i, &c, p->size, p->is_float, p->is_signed, &v)) != IC_OK ||
                (r = check_value(f, e, p, i, -1, v)) != IC_OK)
                return r;
            continue;
        }
        if ((r = ascii_value(f, e, p, i, &c, p->count_size, 0, p->count_signed, &v)) != IC_OK ||
            (r = check_value(f, e, p, i, -1, v)) != IC_OK)
            return r;
        long items = (long)v;
        for (long j = 0; j < items; ++j)
            if ((r = ascii_value(f, e, p, i, &c, p->size, p->is_float, p->is_signed, &v)) != IC_OK ||
                (r = check_value(f, e, p, i, j, v)) != IC_OK)
                return r;
    }
    while (*c == ' ' || *c == '\t')
        ++c;
    if (*c)
        return ic_error_set(f->err, IC_ERR_PARSE, "%s:%ld: %s %llu has more values than its properties (from "
                            "'%.20s'); one instance per line: fix the line or export the mesh again", f->path, f->line,
                            e->name, i + 1, c);
    return face_texcoords(f, e, i);
}

ic_result ic_ply_check(FILE *fp, const char *path, unsigned long long max_elements, ic_error *err)
{
    char magic[5] = "";
    size_t got = fread(magic, 1, 4, fp);
    if (got < 3 || memcmp(magic, "ply", 3))
        return ic_error_set(err, IC_ERR_PARSE, "%s: not a PLY file (it must start with the line 'ply'); export the "
                            "mesh again as PLY", path);
    if (got == 4 && magic[3] == '\r') {
        int ch = getc(fp);
        magic[3] = (char)(ch == '\n' ? '\n' : '?');
    }
    if (got < 4 || magic[3] != '\n')
        return ic_error_set(err, IC_ERR_PARSE, "%s:1: the first line of a PLY file must be exactly 'ply'; fix it or "
                            "export the mesh again", path);
    ply_file *f = calloc(1, sizeof *f);
    if (!f)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory", path);
    f->fp = fp;
    f->path = path;
    f->err = err;
    ic_result r = IC_OK;
    if (!read_header(f))
        r = err ? err->code : IC_ERR_PARSE;
    for (int i = 0; r == IC_OK && i < f->el_count; ++i) {
        const ply_element *e = &f->el[i];
        if (e->count > max_elements)
            r = ic_error_set(err, IC_ERR_UNSUPPORTED,
                             "%s: the PLY header declares %llu of element '%s', more than the limit of %llu; raise "
                             "it with --max-mesh-elements (max_mesh_elements of ic_scene_load_options) if the "
                             "mesh is really this large",
                             path, e->count, e->name, max_elements);
        else if (e->count > 0 && e->prop_count == 0)
            r = ic_error_set(err, IC_ERR_PARSE, "%s: PLY element '%s' has %llu instances but no property; fix the "
                             "header", path, e->name, e->count);
        if (!strcmp(e->name, "vertex"))
            f->vertices = e->count;
        int texcoord_list = 0, index_list = 0;
        for (int k = 0; k < e->prop_count; ++k) {
            texcoord_list |= e->props[k].count_size && e->props[k].attribute;
            index_list |= e->props[k].is_index;
        }
        if (r == IC_OK && e->count > 0 && texcoord_list && !index_list)
            r = ic_error_set(err, IC_ERR_PARSE, "%s: PLY element '%s' has a list 'texcoord' but no vertex index list "
                             "(vertex_indices), and the importer makes faces without vertices of it; add the vertex "
                             "indices or remove the list", path, e->name);
        if (r == IC_OK && !ply_known_element(e->name) && (e->count > 0 || isdigit((unsigned char)e->name[0]))) {
            int later = 0;
            for (int k = i + 1; k < f->el_count; ++k)
                later |= f->el[k].count > 0;
            if (later || isdigit((unsigned char)e->name[0]))
                r = ic_error_set(err, IC_ERR_UNSUPPORTED,
                                 "%s: PLY element '%s' (%llu instances) is not one the importer reads (vertex, face, "
                                 "tristrips, edge, material), and it misreads what follows such an element (or, for "
                                 "a name that begins with digits, takes them for its count); remove it or move it "
                                 "after the others, under a name that begins with a letter",
                                 path, e->name, e->count);
        }
    }
    if (r == IC_OK && f->format == 0 && (f->text = malloc(PLY_MAX_ASCII_LINE)) == NULL)
        r = ic_error_set(err, IC_ERR_OOM, "%s: out of memory", path);
    if (r == IC_OK) {
        flockfile(fp); /* the ascii body is read a byte at a time */
        for (int k = 0; r == IC_OK && k < f->el_count; ++k)
            for (unsigned long long i = 0; r == IC_OK && i < f->el[k].count; ++i)
                r = f->format == 0 ? ascii_instance(f, &f->el[k], i) : binary_instance(f, &f->el[k], i);
        funlockfile(fp);
    }
    free(f->text);
    free(f);
    return r;
}
