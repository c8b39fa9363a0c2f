/*
 * mesh_check_gltf.c — a glTF file's framing and embedded data checked before it is imported (Khronos
 * glTF 2.0 specification §4.4, "GLB File Format Specification", and §3.6.1.1, data URIs; RFC 4648 §4,
 * base64).
 *
 * - Binary glTF: a 12-byte header (magic "glTF", version 2, the total length) and chunks of an 8-byte
 *   header (length, type) and their data, the first one JSON. The importer allocates what the lengths
 *   declare before it reads anything, so a 516-byte file declaring a 2.8 GB JSON chunk (found by the
 *   mesh_glb fuzz target) allocated 2.8 GB; here every length is checked against the bytes the file holds,
 *   and the total against a header and a chunk (a total of 0 let a 4 GB chunk through to the importer,
 *   found by the fuzz stage of the test suite). assimp reads a file as binary by its magic, whatever the
 *   extension, so a .gltf is checked the same way; a file shorter than the header is refused (assimp read
 *   past the end of a 20-byte .gltf beginning "glTF": found by the mesh_gltf fuzz target).
 * - Data URIs ("data:...;base64,..." in a buffer's or an image's uri): assimp 5.2's base64 decoder
 *   allocates the output and then throws on a character outside the alphabet (or a length that is not a
 *   multiple of 4), leaking the output (found by the mesh_gltf fuzz target: a replacement character in a
 *   buffer's data); here the text is checked first, and a buffer's decoded length against its byteLength.
 * - A buffer in a file of its own (uri "tri.bin"): assimp throws when the file is shorter than the
 *   buffer's byteLength and leaks the stream it opened (found by the mesh_gltf fuzz target: byteLength 45
 *   for a 44-byte file); here the file's size is compared first.
 */
#include "scene/mesh_check.h"

#include <cjson/cJSON.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static ic_result check_json(FILE *fp, const char *path, ic_error *err);

/* Largest JSON text read for the checks: 1 GiB, since a .gltf may hold its buffers inline as base64 (a
 * larger one is refused: its buffers belong in .bin files or a .glb). */
#define GLTF_MAX_JSON ((size_t)1 << 30)

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

ic_result ic_glb_check(FILE *fp, const char *path, ic_error *err)
{
    unsigned char h[12];
    if (fseek(fp, 0, SEEK_END) != 0)
        return IC_OK; /* not seekable: the importer reports what it finds */
    long size = ftell(fp);
    size_t got = size < 0 || fseek(fp, 0, SEEK_SET) != 0 ? 0 : fread(h, 1, sizeof h, fp);
    if (got < 4 || memcmp(h, "glTF", 4))
        return ic_error_set(err, IC_ERR_PARSE, "%s: not binary glTF (it does not begin with 'glTF'); a text glTF "
                            "file is named .gltf: rename it or export the model again", path);
    if (got < sizeof h) /* assimp reads the header past the end of such a file (found by the fuzzer) */
        return ic_error_set(err, IC_ERR_PARSE, "%s: a binary glTF file of %ld bytes, shorter than its 12-byte "
                            "header; the file is truncated: export it again", path, size);
    uint32_t total = le32(h + 8);
    if (le32(h + 4) != 2)
        return ic_error_set(err, IC_ERR_PARSE, "%s: binary glTF version %u; only version 2 is read (export it as "
                            "glTF 2.0)", path, le32(h + 4));
    if (total > (uint64_t)size)
        return ic_error_set(err, IC_ERR_PARSE, "%s: the binary glTF header declares %u bytes but the file holds %ld; "
                            "the file is truncated or corrupt: export it again", path, total, size);
    if (total < 12 + 8) /* no room for the JSON chunk's header: the chunk walk below would check nothing */
        return ic_error_set(err, IC_ERR_PARSE, "%s: the binary glTF header declares %u bytes, too few for a header "
                            "and a JSON chunk; the file is corrupt: export it again", path, total);
    /* The JSON chunk at byte 12, then (where the total leaves room for its header) the BIN chunk after the
     * JSON padded to 4 bytes, where the importer looks for it. */
    for (uint64_t at = 12, k = 0; k < 2 && at + 8 <= total; ++k) {
        unsigned char c[8];
        if (fseek(fp, (long)at, SEEK_SET) != 0 || fread(c, 1, sizeof c, fp) != sizeof c)
            return ic_error_set(err, IC_ERR_PARSE, "%s: cannot read the chunk header at byte %llu; export the file "
                                "again", path, (unsigned long long)at);
        uint64_t len = le32(c);
        if (memcmp(c + 4, k == 0 ? "JSON" : "BIN\0", 4))
            return ic_error_set(err, IC_ERR_PARSE, "%s: the %s chunk of a binary glTF must be %s; export the file "
                                "again", path, k == 0 ? "first" : "second", k == 0 ? "JSON" : "BIN");
        if (at + 8 + len > total)
            return ic_error_set(err, IC_ERR_PARSE, "%s: the chunk at byte %llu declares %llu bytes, past the file's "
                                "%u; the file is truncated or corrupt: export it again", path,
                                (unsigned long long)at, (unsigned long long)len, total);
        at += 8 + ((len + 3) & ~(uint64_t)3);
    }
    return check_json(fp, path, err);
}

char *ic_gltf_json(FILE *fp, size_t *len)
{
    *len = 0;
    unsigned char head[20];
    char *text = NULL;
    if (fseek(fp, 0, SEEK_SET) != 0)
        return NULL;
    if (fread(head, 1, sizeof head, fp) == sizeof head && !memcmp(head, "glTF", 4)) {
        /* .glb: 12-byte header, then chunk 0 = (length, "JSON", bytes) */
        uint32_t chunk = le32(head + 12);
        if (!memcmp(head + 16, "JSON", 4) && chunk < GLTF_MAX_JSON && (text = malloc(chunk + 1u)) != NULL)
            *len = fread(text, 1, chunk, fp);
    } else if (fseek(fp, 0, SEEK_END) == 0) {
        long size = ftell(fp);
        if (size > 0 && (size_t)size < GLTF_MAX_JSON && fseek(fp, 0, SEEK_SET) == 0 &&
            (text = malloc((size_t)size + 1)) != NULL)
            *len = fread(text, 1, (size_t)size, fp);
    }
    if (text)
        text[*len] = '\0';
    return text;
}

/* The first position in data of a character that is not base64 (or where padding is wrong), or len if
 * the text is valid: the alphabet, then at most two '=' at the end, a multiple of 4 in all. */
static size_t base64_error(const char *data, size_t len)
{
    size_t i = 0;
    for (; i < len; ++i) {
        unsigned char c = (unsigned char)data[i];
        if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' || c == '/'))
            break;
    }
    size_t pad = 0;
    while (i + pad < len && data[i + pad] == '=' && pad < 2)
        ++pad;
    if (i + pad != len)
        return i + pad;
    return len % 4 ? len : len + 1; /* len + 1: valid */
}

/* A buffer in a file of its own: no shorter than its byteLength (assimp throws when it is, and leaks the
 * file it opened). A file that is not there is left to the importer's message. */
static ic_result check_buffer_file(const char *path, int i, const char *uri, double byte_length, ic_error *err)
{
    char file[4096];
    const char *slash = strrchr(path, '/');
    int dir_len = slash ? (int)(slash - path) + 1 : 0;
    if (uri[0] == '/' || snprintf(file, sizeof file, "%.*s%s", dir_len, path, uri) >= (int)sizeof file)
        return IC_OK;
    struct stat st;
    if (stat(file, &st) != 0 || !S_ISREG(st.st_mode) || (double)st.st_size >= byte_length)
        return IC_OK;
    return ic_error_set(err, IC_ERR_PARSE, "%s: buffers[%d]: byteLength is %.0f but '%s' holds %lld bytes; the "
                        "buffer file is truncated or the wrong one: export the model again", path, i, byte_length,
                        uri, (long long)st.st_size);
}

/* Longest header of a data URI ("data:" to ','): assimp 5.2 keeps the offsets of its parts in signed chars,
 * so past 127 they wrap and it decodes from elsewhere in the text, throws and leaks its buffer (found by the
 * mesh_gltf fuzz target: a 170-character media type). */
#define DATA_URI_MAX_HEAD 120

/* Checks the URIs of array `name` ("buffers", "images"): data URIs hold valid base64 (of a buffer's
 * byteLength), a buffer's file is as long as its byteLength. */
static ic_result check_uris(const cJSON *root, const char *name, const char *path, ic_error *err)
{
    const cJSON *list = cJSON_GetObjectItemCaseSensitive(root, name);
    int i = 0;
    for (const cJSON *item = cJSON_IsArray(list) ? list->child : NULL; item; item = item->next, ++i) {
        const cJSON *uri = cJSON_GetObjectItemCaseSensitive(item, "uri");
        const cJSON *byte_length = cJSON_GetObjectItemCaseSensitive(item, "byteLength");
        double want = cJSON_IsNumber(byte_length) ? byte_length->valuedouble : 0.0;
        if (!cJSON_IsString(uri))
            continue;
        if (strncmp(uri->valuestring, "data:", 5)) {
            ic_result r = want > 0.0 && !strcmp(name, "buffers")
                              ? check_buffer_file(path, i, uri->valuestring, want, err) : IC_OK;
            if (r != IC_OK)
                return r;
            continue;
        }
        const char *comma = strchr(uri->valuestring, ',');
        if (!comma)
            return ic_error_set(err, IC_ERR_PARSE, "%s: %s[%d]: a data URI without ',' before its data; export the "
                                "file again", path, name, i);
        size_t head = (size_t)(comma - uri->valuestring);
        if (head > DATA_URI_MAX_HEAD)
            return ic_error_set(err, IC_ERR_PARSE, "%s: %s[%d]: a data URI whose media type and parameters (before "
                                "',') run to %zu characters, more than %d; shorten them (data:application/octet-"
                                "stream;base64,...)", path, name, i, head, DATA_URI_MAX_HEAD);
        if (head < 7 || strncmp(comma - 7, ";base64", 7))
            continue; /* not base64: percent-encoded text, which assimp does not decode */
        const char *data = comma + 1;
        size_t len = strlen(data), at = base64_error(data, len);
        if (at == len)
            return ic_error_set(err, IC_ERR_PARSE, "%s: %s[%d]: the base64 data of its URI is %zu characters, not a "
                                "multiple of 4; the file is corrupt: export it again", path, name, i, len);
        if (at < len)
            return ic_error_set(err, IC_ERR_PARSE, "%s: %s[%d]: character %zu of the base64 data of its URI is "
                                "not base64 (0x%02x); the file is corrupt: export it again", path, name, i, at + 1,
                                (unsigned char)data[at]);
        size_t bytes = len / 4 * 3 - (len && data[len - 1] == '=') - (len > 1 && data[len - 2] == '=');
        if (want > 0.0 && (double)bytes != want && !strcmp(name, "buffers"))
            return ic_error_set(err, IC_ERR_PARSE, "%s: buffers[%d]: byteLength is %.0f but its data URI holds %zu "
                                "bytes; the file is corrupt: export it again", path, i, want, bytes);
    }
    return IC_OK;
}

/* ---- The JSON text as the importer's parser (rapidjson, default flags) takes it --------------------- */

/* RFC 8259's grammar, strictly: if any of it fails, assimp's glTF importer declines the file and assimp
 * offers it to every other importer by content, one of which (OpenGEX) looped for ever or read past its
 * buffer on a fuzzed file. No control character outside whitespace (none unescaped in a string), numbers
 * without leading zeros or a bare point, at most JSON_MAX_DEPTH nested values, only whitespace after the
 * root. The text ends at its first NUL, as the importer's in-place parse does. Returns the offset of the
 * first error, or len if the text is valid. */
#define JSON_MAX_DEPTH 512

typedef struct json_in {
    const char *s;
    size_t i, len;
} json_in;

static void json_ws(json_in *in)
{
    while (in->i < in->len && (in->s[in->i] == ' ' || in->s[in->i] == '\t' || in->s[in->i] == '\n' ||
                               in->s[in->i] == '\r'))
        ++in->i;
}

static int json_digits(json_in *in)
{
    size_t from = in->i;
    while (in->i < in->len && in->s[in->i] >= '0' && in->s[in->i] <= '9')
        ++in->i;
    return in->i > from;
}

static int json_string(json_in *in)
{
    ++in->i; /* the opening quote */
    while (in->i < in->len) {
        unsigned char c = (unsigned char)in->s[in->i++];
        if (c == '"')
            return 1;
        if (c < 0x20)
            return 0;
        if (c == '\\') {
            if (in->i >= in->len)
                return 0;
            c = (unsigned char)in->s[in->i++];
            if (c == 'u') {
                for (int k = 0; k < 4; ++k, ++in->i)
                    if (in->i >= in->len || !strchr("0123456789abcdefABCDEF", in->s[in->i]) || !in->s[in->i])
                        return 0;
            } else if (!strchr("\"\\/bfnrt", c) || !c) {
                return 0;
            }
        }
    }
    return 0;
}

static int json_value(json_in *in, int depth)
{
    json_ws(in);
    if (in->i >= in->len || depth > JSON_MAX_DEPTH)
        return 0;
    char c = in->s[in->i];
    if (c == '{' || c == '[') {
        char close = c == '{' ? '}' : ']';
        ++in->i;
        json_ws(in);
        if (in->i < in->len && in->s[in->i] == close) {
            ++in->i;
            return 1;
        }
        for (;;) {
            if (c == '{') {
                json_ws(in);
                if (in->i >= in->len || in->s[in->i] != '"' || !json_string(in))
                    return 0;
                json_ws(in);
                if (in->i >= in->len || in->s[in->i++] != ':')
                    return 0;
            }
            if (!json_value(in, depth + 1))
                return 0;
            json_ws(in);
            if (in->i >= in->len)
                return 0;
            char d = in->s[in->i++];
            if (d == close)
                return 1;
            if (d != ',')
                return 0;
        }
    }
    if (c == '"')
        return json_string(in);
    if (c == '-' || (c >= '0' && c <= '9')) {
        if (c == '-')
            ++in->i;
        if (in->i < in->len && in->s[in->i] == '0')
            ++in->i;
        else if (!json_digits(in))
            return 0;
        if (in->i < in->len && in->s[in->i] == '.' && (++in->i, !json_digits(in)))
            return 0;
        if (in->i < in->len && (in->s[in->i] == 'e' || in->s[in->i] == 'E')) {
            ++in->i;
            if (in->i < in->len && (in->s[in->i] == '+' || in->s[in->i] == '-'))
                ++in->i;
            if (!json_digits(in))
                return 0;
        }
        return 1;
    }
    static const char *const words[] = {"true", "false", "null"};
    for (int k = 0; k < 3; ++k) {
        size_t n = strlen(words[k]);
        if (in->len - in->i >= n && !memcmp(in->s + in->i, words[k], n)) {
            in->i += n;
            return 1;
        }
    }
    return 0;
}

static size_t json_error_at(const char *text, size_t len)
{
    const char *nul = memchr(text, '\0', len);
    json_in in = {text, 0, nul ? (size_t)(nul - text) : len};
    if (!json_value(&in, 0))
        return in.i;
    json_ws(&in);
    return in.i == in.len ? len : in.i;
}

/* ---- Accessors and buffer views against the data they read (glTF 2.0 §3.6, §5.1, §5.11) ------------ */

/* Whether it is a whole number in [lo, hi]. */
static int whole_value(const cJSON *it, double lo, double hi)
{
    return cJSON_IsNumber(it) && it->valuedouble == floor(it->valuedouble) && it->valuedouble >= lo &&
           it->valuedouble <= hi;
}

/* obj[key] as a whole number in [lo, hi]: 1, 0 if absent (*v = dflt), -1 if present but not such a number. */
static int whole(const cJSON *obj, const char *key, double lo, double hi, double dflt, double *v)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
    *v = dflt;
    if (!it)
        return 0;
    if (!whole_value(it, lo, hi))
        return -1;
    *v = it->valuedouble;
    return 1;
}

static int array_size(const cJSON *root, const char *key)
{
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(root, key);
    return cJSON_IsArray(a) ? cJSON_GetArraySize(a) : 0;
}

/* Bytes of one element of an accessor: componentType's size times the type's components, a matrix's
 * columns each padded to 4 bytes (§3.6.2.4); 0 for an unknown type. */
static double element_bytes(double component_type, const char *type)
{
    static const struct { int code, size; } comps[] = {{5120, 1}, {5121, 1}, {5122, 2}, {5123, 2}, {5125, 4}, {5126, 4}};
    static const struct { const char *name; int rows, cols; } types[] = {
        {"SCALAR", 1, 1}, {"VEC2", 2, 1}, {"VEC3", 3, 1}, {"VEC4", 4, 1}, {"MAT2", 2, 2}, {"MAT3", 3, 3}, {"MAT4", 4, 4}};
    int size = 0;
    for (size_t k = 0; k < sizeof comps / sizeof comps[0]; ++k)
        if (component_type == comps[k].code)
            size = comps[k].size;
    for (size_t k = 0; size && type && k < sizeof types / sizeof types[0]; ++k)
        if (!strcmp(type, types[k].name)) {
            int column = types[k].rows * size;
            if (types[k].cols > 1)
                column = (column + 3) & ~3;
            return (double)column * types[k].cols;
        }
    return 0.0;
}

/* assimp 5.2 reads an accessor's elements with few checks and throws on some bad ones while it holds what it
 * allocated (found by the mesh_glb fuzz target: an index accessor without a valid count read past its
 * view, "Invalid index 2, count out of range", 24 bytes leaked). So every view lies within its buffer,
 * every accessor has a count, a component type and a type, and reads within its view, and every index a
 * mesh primitive gives names an accessor. */
static ic_result check_accessors(const cJSON *root, const char *path, ic_error *err)
{
    const double big = 9007199254740992.0; /* 2^53: any size a JSON number holds exactly */
    int nb = array_size(root, "buffers"), nv = array_size(root, "bufferViews"), na = array_size(root, "accessors");
    const cJSON *buffers = cJSON_GetObjectItemCaseSensitive(root, "buffers");
    const cJSON *views = cJSON_GetObjectItemCaseSensitive(root, "bufferViews");
    int i = 0;
    for (const cJSON *v = nv ? views->child : NULL; v; v = v->next, ++i) {
        double buffer = 0.0, length = 0.0, offset = 0.0, stride = 0.0, buffer_length = 0.0;
        if (whole(v, "buffer", 0, nb - 1, 0, &buffer) != 1 || whole(v, "byteLength", 1, big, 0, &length) != 1 ||
            whole(v, "byteOffset", 0, big, 0, &offset) < 0 || whole(v, "byteStride", 4, 252, 0, &stride) < 0)
            return ic_error_set(err, IC_ERR_PARSE, "%s: bufferViews[%d]: needs a buffer (0 to %d), a byteLength >= 1, "
                                "and if given a byteOffset >= 0 and a byteStride of 4 to 252; export the model again",
                                path, i, nb - 1);
        const cJSON *b = cJSON_GetArrayItem(buffers, (int)buffer);
        if (whole(b, "byteLength", 1, big, -1, &buffer_length) == 1 && offset + length > buffer_length)
            return ic_error_set(err, IC_ERR_PARSE, "%s: bufferViews[%d]: bytes %.0f to %.0f, past the end of buffers[%.0f]"
                                " (%.0f bytes); export the model again", path, i, offset, offset + length, buffer,
                                buffer_length);
    }
    i = 0;
    const cJSON *accessors = cJSON_GetObjectItemCaseSensitive(root, "accessors");
    for (const cJSON *a = na ? accessors->child : NULL; a; a = a->next, ++i) {
        double count = 0.0, component = 0.0, view = -1.0, offset = 0.0;
        const cJSON *type = cJSON_GetObjectItemCaseSensitive(a, "type");
        double elem = 0.0;
        if (whole(a, "count", 1, big, 0, &count) != 1 || whole(a, "componentType", 0, big, 0, &component) != 1 ||
            (elem = element_bytes(component, cJSON_IsString(type) ? type->valuestring : NULL)) == 0.0 ||
            whole(a, "bufferView", 0, nv - 1, -1, &view) < 0 || whole(a, "byteOffset", 0, big, 0, &offset) < 0)
            return ic_error_set(err, IC_ERR_PARSE, "%s: accessors[%d]: needs a count >= 1, a componentType (5120 to "
                                "5126), a type (SCALAR, VEC2 to VEC4, MAT2 to MAT4), and if given a bufferView (0 to "
                                "%d) and a byteOffset >= 0; export the model again", path, i, nv - 1);
        const cJSON *sparse = cJSON_GetObjectItemCaseSensitive(a, "sparse");
        if (sparse) {
            /* count replaced elements: their indices (one component each) and values read within their views */
            const cJSON *ix = cJSON_GetObjectItemCaseSensitive(sparse, "indices");
            const cJSON *vals = cJSON_GetObjectItemCaseSensitive(sparse, "values");
            double sc = 0.0, iv = 0.0, io = 0.0, ict = 0.0, vv = 0.0, vo = 0.0, il = 0.0, vl = 0.0;
            double isz = 0.0;
            int ok = whole(sparse, "count", 1, count, 0, &sc) == 1 && whole(ix, "bufferView", 0, nv - 1, 0, &iv) == 1 &&
                     whole(ix, "byteOffset", 0, big, 0, &io) >= 0 && whole(ix, "componentType", 0, big, 0, &ict) == 1 &&
                     (isz = element_bytes(ict, "SCALAR")) > 0.0 && ict != 5120 && ict != 5122 && ict != 5126 &&
                     whole(vals, "bufferView", 0, nv - 1, 0, &vv) == 1 && whole(vals, "byteOffset", 0, big, 0, &vo) >= 0;
            if (ok) {
                whole(cJSON_GetArrayItem(views, (int)iv), "byteLength", 1, big, 0, &il);
                whole(cJSON_GetArrayItem(views, (int)vv), "byteLength", 1, big, 0, &vl);
                ok = io + isz * sc <= il && vo + elem * sc <= vl;
            }
            if (!ok)
                return ic_error_set(err, IC_ERR_PARSE, "%s: accessors[%d]: its sparse part needs a count (1 to the "
                                    "accessor's), indices (an unsigned componentType) and values in bufferViews that "
                                    "hold them; export the model again", path, i);
        }
        if (view < 0)
            continue; /* no view: all zeros, or a sparse accessor's base */
        const cJSON *v = cJSON_GetArrayItem(views, (int)view);
        double length = 0.0, stride = 0.0;
        whole(v, "byteLength", 1, big, 0, &length);
        whole(v, "byteStride", 4, 252, 0, &stride);
        double end = offset + (stride > 0.0 ? stride : elem) * (count - 1.0) + elem;
        if (end > length)
            return ic_error_set(err, IC_ERR_PARSE, "%s: accessors[%d]: %.0f elements of %.0f bytes from byte %.0f read to "
                                "byte %.0f of bufferViews[%.0f], which has %.0f; export the model again", path, i,
                                count, elem, offset, end, view, length);
    }
    i = 0;
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(root, "meshes");
    for (const cJSON *m = cJSON_IsArray(meshes) ? meshes->child : NULL; m; m = m->next, ++i) {
        const cJSON *prims = cJSON_GetObjectItemCaseSensitive(m, "primitives");
        for (const cJSON *p = cJSON_IsArray(prims) ? prims->child : NULL; p; p = p->next) {
            double index;
            int bad = whole(p, "indices", 0, na - 1, 0, &index) < 0;
            const cJSON *attrs = cJSON_GetObjectItemCaseSensitive(p, "attributes");
            for (const cJSON *at = cJSON_IsObject(attrs) ? attrs->child : NULL; at && !bad; at = at->next)
                bad = !whole_value(at, 0, na - 1);
            if (bad)
                return ic_error_set(err, IC_ERR_PARSE, "%s: meshes[%d]: a primitive's indices or attributes name no "
                                    "accessor (there are %d); export the model again", path, i, na);
        }
    }
    /* every other reference by index names an element of its array */
    static const struct { const char *array, *key, *target; } refs[] = {
        {"textures", "source", "images"}, {"textures", "sampler", "samplers"}, {"images", "bufferView", "bufferViews"},
        {"nodes", "mesh", "meshes"}, {"nodes", "camera", "cameras"}, {"nodes", "skin", "skins"}, {"scene", NULL, "scenes"},
    };
    for (size_t k = 0; k < sizeof refs / sizeof refs[0]; ++k) {
        int n = array_size(root, refs[k].target);
        double v;
        if (!refs[k].key) { /* a top-level index */
            if (whole(root, refs[k].array, 0, n - 1, 0, &v) < 0)
                return ic_error_set(err, IC_ERR_PARSE, "%s: \"%s\" names no element of \"%s\" (there are %d); export "
                                    "the model again", path, refs[k].array, refs[k].target, n);
            continue;
        }
        const cJSON *arr = cJSON_GetObjectItemCaseSensitive(root, refs[k].array);
        i = 0;
        for (const cJSON *e = cJSON_IsArray(arr) ? arr->child : NULL; e; e = e->next, ++i)
            if (whole(e, refs[k].key, 0, n - 1, 0, &v) < 0)
                return ic_error_set(err, IC_ERR_PARSE, "%s: %s[%d]: \"%s\" names no element of \"%s\" (there are %d); "
                                    "export the model again", path, refs[k].array, i, refs[k].key, refs[k].target, n);
    }
    /* node children and scene roots name nodes; primitives' materials name materials */
    int nn = array_size(root, "nodes"), nm = array_size(root, "materials");
    static const struct { const char *array, *list; } lists[] = {{"nodes", "children"}, {"scenes", "nodes"}};
    for (size_t k = 0; k < sizeof lists / sizeof lists[0]; ++k) {
        const cJSON *arr = cJSON_GetObjectItemCaseSensitive(root, lists[k].array);
        i = 0;
        for (const cJSON *e = cJSON_IsArray(arr) ? arr->child : NULL; e; e = e->next, ++i) {
            const cJSON *l = cJSON_GetObjectItemCaseSensitive(e, lists[k].list);
            for (const cJSON *x = cJSON_IsArray(l) ? l->child : NULL; x; x = x->next)
                if (!whole_value(x, 0, nn - 1))
                    return ic_error_set(err, IC_ERR_PARSE, "%s: %s[%d]: \"%s\" names no node (there are %d); export "
                                        "the model again", path, lists[k].array, i, lists[k].list, nn);
        }
    }
    i = 0;
    for (const cJSON *m = cJSON_IsArray(meshes) ? meshes->child : NULL; m; m = m->next, ++i) {
        const cJSON *prims = cJSON_GetObjectItemCaseSensitive(m, "primitives");
        for (const cJSON *p = cJSON_IsArray(prims) ? prims->child : NULL; p; p = p->next) {
            double v;
            if (whole(p, "material", 0, nm - 1, 0, &v) < 0)
                return ic_error_set(err, IC_ERR_PARSE, "%s: meshes[%d]: a primitive's material names no material "
                                    "(there are %d); export the model again", path, i, nm);
        }
    }
    return IC_OK;
}

/* The JSON of a glTF file (ic_gltf_json: a .gltf's text, a .glb's JSON chunk) as the importer needs it. */
static ic_result check_json(FILE *fp, const char *path, ic_error *err)
{
    size_t len;
    char *text = ic_gltf_json(fp, &len);
    if (!text)
        return ic_error_set(err, IC_ERR_PARSE, "%s: no glTF JSON could be read (empty, or larger than %zu MiB: keep "
                            "the buffers in .bin files, or export a .glb)", path, GLTF_MAX_JSON >> 20);
    size_t at = json_error_at(text, len);
    cJSON *root = at == len ? cJSON_ParseWithLength(text, len) : NULL;
    free(text);
    if (!root)
        return ic_error_set(err, IC_ERR_PARSE, "%s: the glTF JSON is not valid JSON at byte %zu of its text; export "
                            "the model again", path, (at < len ? at : 0) + 1);
    /* The importer takes only an object whose "asset" object has a "version" string beginning with 2. */
    const cJSON *asset = cJSON_IsObject(root) ? cJSON_GetObjectItemCaseSensitive(root, "asset") : NULL;
    const cJSON *version = cJSON_IsObject(asset) ? cJSON_GetObjectItemCaseSensitive(asset, "version") : NULL;
    ic_result r = IC_OK;
    if (!cJSON_IsString(version) || version->valuestring[0] != '2')
        r = ic_error_set(err, IC_ERR_PARSE, "%s: not a glTF 2.0 file (no \"asset\": {\"version\": \"2.0\"}); "
                         "export it as glTF 2.0", path);
    if (r == IC_OK)
        r = check_uris(root, "buffers", path, err);
    if (r == IC_OK)
        r = check_uris(root, "images", path, err);
    if (r == IC_OK)
        r = check_accessors(root, path, err);
    cJSON_Delete(root);
    return r;
}

ic_result ic_gltf_check(FILE *fp, const char *path, ic_error *err)
{
    unsigned char magic[4];
    if (fseek(fp, 0, SEEK_SET) == 0 && fread(magic, 1, 4, fp) == 4 && !memcmp(magic, "glTF", 4))
        return ic_error_set(err, IC_ERR_PARSE, "%s: binary glTF in a file named .gltf (the importer reads a .gltf "
                            "as text); rename it .glb", path);
    return check_json(fp, path, err);
}
