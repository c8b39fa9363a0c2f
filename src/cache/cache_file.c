/*
 * cache_file.c — the cache file: versioned, checksummed, tied to one scene and one
 * set of cache parameters, written atomically (core/atomic_file.h).
 *
 * Layout, all little-endian, floats as IEEE-754 bit patterns (so a round trip is bit-exact):
 *   0   char[8]  magic "IRRCACHE"
 *   8   u32      format version (IC_CACHE_FILE_VERSION)
 *   12  u32      bytes of the parameter block (PARAM_BYTES)
 *   16  u64      scene hash (caller-supplied)
 *   24  …        parameter block: the parameters that shaped the records (weight, accuracy, radius
 *                bounds, clamp switches and their parameters); look-up-only settings (final
 *                acceptance, behind tolerance, octree shape, threads) are free to change
 *   80  u64      record count N
 *   88  u32      (version 4) bytes L of the settings text, at most IC_CACHE_MAX_SETTINGS_BYTES
 *   92  L bytes  (version 4) the settings text (cache.h: SETTINGS TEXT; empty from ic_cache_save); the
 *                records follow it (at 88 before version 4)
 *   …   N × 172  records: p (3f), R, n (3f), a, E (3f), ∇r E (9f), ∇t E (9f), tangent (3f), σ (3f),
 *                harmonic-mean distance, pixel footprint, change count (u32), bounce (u8), flags (u8),
 *                2 zero bytes, then (version 3) the elliptical extent's squeeze k (3f) and ratio ρ
 *                (cache.h: ELLIPTICAL RECORDS; 0, 0, 0, 1 for a round record); 156 bytes before version 3
 *   …   u64      (version 2) payload floats P in all records
 *   …   N × u32  (version 2) each record's payload length (0: none; cache.h ic_cache_set_payload)
 *   …   P × f32  (version 2) the payloads in record order
 *   end u64      FNV-1a 64 of every byte before it
 * Version 1 files (no payload section), version 2 files (no ellipses: every record round) and version 3
 * files (no settings text: a refusal for another scene or settings gives the two hashes) still load.
 * The octree is not stored: loading rebuilds it from the records.
 */
#include "cache_store.h"

#include "core/atomic_file.h"
#include "core/read_file.h"
#include "core/text.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define IC_CACHE_FILE_VERSION 4u
#define IC_CACHE_FILE_OLDEST 1u /* the oldest version still read */
#define MAGIC "IRRCACHE"
#define PARAM_BYTES 56u
#define HEADER_BYTES (24u + PARAM_BYTES + 8u)
#define RECORD_BYTES 172u
#define RECORD_BYTES_V2 156u /* versions 1 and 2: no squeeze */
/* What to do, by what is wrong. A damaged file is rebuilt; a sound one made for other settings is kept (the
 * settings may be what is wrong); a file that is no cache file at all is the user's, not ours to delete. */
#define REBUILD_HINT "delete it and build the cache again"
#define MISMATCH_HINT "use the scene and settings it was made with, or build the cache again"
#define REBUILD_INSTEAD "or build the cache again instead of loading it"
#define SCENE_KEY "scene"
#define SCENE_NAME_KEY "scene file"
#define SAID_BYTES 96 /* most bytes of a key or value a message quotes (three options fit one message) */
#define NOT_CACHE_HINT "give the path of a cache file (ic_cache_save and --save-cache write them)"

/* ---- little-endian encoding ------------------------------------------------------------------- */

static void put_u32(unsigned char *b, uint32_t v)
{
    for (int k = 0; k < 4; ++k)
        b[k] = (unsigned char)(v >> (8 * k));
}
static void put_u64(unsigned char *b, uint64_t v)
{
    for (int k = 0; k < 8; ++k)
        b[k] = (unsigned char)(v >> (8 * k));
}
static void put_f32(unsigned char *b, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    put_u32(b, v);
}
static uint32_t get_u32(const unsigned char *b)
{
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k)
        v |= (uint32_t)b[k] << (8 * k);
    return v;
}
static uint64_t get_u64(const unsigned char *b)
{
    uint64_t v = 0;
    for (int k = 0; k < 8; ++k)
        v |= (uint64_t)b[k] << (8 * k);
    return v;
}
static float get_f32(const unsigned char *b)
{
    uint32_t v = get_u32(b);
    float f;
    memcpy(&f, &v, 4);
    return f;
}

/* Fields of the parameter block, in file order, with their names for mismatch messages. */
enum { N_PARAM_FIELDS = 14 };
enum { FIELD_U32, FIELD_FLOAT, FIELD_SWITCH, FIELD_WEIGHT }; /* how a field is stored and said */
typedef struct param_field {
    const char *name;
    int kind;
    float f;
    uint32_t u;
} param_field;

static void param_fields(const ic_cache_params *p, param_field out[N_PARAM_FIELDS])
{
    const param_field f[N_PARAM_FIELDS] = {
        {"weight", FIELD_WEIGHT, 0.0f, (uint32_t)p->weight},
        {"accuracy", FIELD_FLOAT, p->accuracy, 0},
        {"min_radius", FIELD_FLOAT, p->min_radius, 0},
        {"max_radius", FIELD_FLOAT, p->max_radius, 0},
        {"min_radius_pixels", FIELD_FLOAT, p->min_radius_pixels, 0},
        {"max_radius_pixels", FIELD_FLOAT, p->max_radius_pixels, 0},
        {"gradient_clamp", FIELD_SWITCH, 0.0f, (uint32_t)p->gradient_clamp},
        {"neighbor_clamp", FIELD_SWITCH, 0.0f, (uint32_t)p->neighbor_clamp},
        {"validity_clamp", FIELD_SWITCH, 0.0f, (uint32_t)p->validity_clamp},
        {"validity_k", FIELD_U32, 0.0f, p->validity_k},
        {"validity_angle_deg", FIELD_FLOAT, p->validity_angle_deg, 0},
        {"gradient_difference", FIELD_SWITCH, 0.0f, (uint32_t)p->gradient_difference},
        {"gradient_difference_threshold", FIELD_FLOAT, p->gradient_difference_threshold, 0},
        {"reserved", FIELD_U32, 0.0f, 0},
    };
    memcpy(out, f, sizeof f);
}

static void encode_params(const ic_cache_params *p, unsigned char *b)
{
    param_field f[N_PARAM_FIELDS];
    param_fields(p, f);
    for (int k = 0; k < N_PARAM_FIELDS; ++k) {
        if (f[k].kind == FIELD_FLOAT)
            put_f32(b + 4 * k, f[k].f);
        else
            put_u32(b + 4 * k, f[k].u);
    }
}

static void encode_record(const ic_cache *c, uint32_t i, unsigned char *b)
{
    const ic_float4 *s = &c->sphere[i], *n = &c->normal[i];
    const ic_record_cold *cd = &c->cold[i];
    float f[37] = {s->x, s->y, s->z, s->w, n->x, n->y, n->z, n->w, cd->irradiance.x, cd->irradiance.y,
                   cd->irradiance.z};
    int k = 11;
    for (int ch = 0; ch < 3; ++ch) {
        f[k++] = cd->grad_rot[ch].x;
        f[k++] = cd->grad_rot[ch].y;
        f[k++] = cd->grad_rot[ch].z;
    }
    for (int ch = 0; ch < 3; ++ch) {
        f[k++] = cd->grad_trans[ch].x;
        f[k++] = cd->grad_trans[ch].y;
        f[k++] = cd->grad_trans[ch].z;
    }
    f[k++] = cd->tangent.x;
    f[k++] = cd->tangent.y;
    f[k++] = cd->tangent.z;
    f[k++] = cd->sigma.x;
    f[k++] = cd->sigma.y;
    f[k++] = cd->sigma.z;
    f[k++] = cd->harmonic_mean_dist;
    f[k++] = cd->pixel_footprint;
    for (k = 0; k < 37; ++k)
        put_f32(b + 4 * k, f[k]);
    put_u32(b + 148, cd->change_count);
    b[152] = cd->bounce;
    b[153] = cd->flags;
    b[154] = b[155] = 0;
    const ic_float4 *e = &c->squeeze[i];
    put_f32(b + 156, e->x);
    put_f32(b + 160, e->y);
    put_f32(b + 164, e->z);
    put_f32(b + 168, e->w);
}

/* The harmonic-mean distance's place among a record's 37 floats: the one field that may be +inf (a record
 * whose rays all missed, gather.h, inserts when max_radius or the pixel bounds make its R finite). */
#define HARMONIC_MEAN_FIELD 35

/* Returns 1 if the decoded record is usable (finite but for an infinite harmonic-mean distance, positive
 * radius and accuracy, unit-ish normal, a ratio in (0, 1] and a squeeze that matches it). has_squeeze: the
 * file's records carry one. */
static int decode_record(ic_cache *c, uint32_t i, const unsigned char *b, int has_squeeze)
{
    float f[37];
    for (int k = 0; k < 37; ++k)
        f[k] = get_f32(b + 4 * k);
    for (int k = 0; k < 37; ++k)
        if (!isfinite(f[k]) && !(k == HARMONIC_MEAN_FIELD && f[k] == INFINITY))
            return 0;
    c->sphere[i] = (ic_float4){f[0], f[1], f[2], f[3]};
    c->normal[i] = (ic_float4){f[4], f[5], f[6], f[7]};
    ic_record_cold *cd = &c->cold[i];
    memset(cd, 0, sizeof *cd);
    cd->irradiance = v3(f[8], f[9], f[10]);
    int k = 11;
    for (int ch = 0; ch < 3; ++ch, k += 3)
        cd->grad_rot[ch] = v3(f[k], f[k + 1], f[k + 2]);
    for (int ch = 0; ch < 3; ++ch, k += 3)
        cd->grad_trans[ch] = v3(f[k], f[k + 1], f[k + 2]);
    cd->tangent = v3(f[k], f[k + 1], f[k + 2]);
    cd->sigma = v3(f[k + 3], f[k + 4], f[k + 5]);
    cd->harmonic_mean_dist = f[k + 6]; /* k + 6 == HARMONIC_MEAN_FIELD */
    cd->pixel_footprint = f[k + 7];
    cd->change_count = get_u32(b + 148);
    cd->bounce = b[152];
    cd->flags = b[153];
    float nl = f[4] * f[4] + f[5] * f[5] + f[6] * f[6];
    ic_float4 e = {0.0f, 0.0f, 0.0f, 1.0f};
    if (has_squeeze)
        e = (ic_float4){get_f32(b + 156), get_f32(b + 160), get_f32(b + 164), get_f32(b + 168)};
    c->squeeze[i] = e;
    /* |k|² = 1/ρ² − 1 within float rounding; a round record has k = 0. */
    float k2 = e.x * e.x + e.y * e.y + e.z * e.z;
    int squeeze_ok = isfinite(k2) && e.w > 0.0f && e.w <= 1.0f &&
                     (e.w == 1.0f ? k2 == 0.0f : fabsf(k2 * e.w * e.w - (1.0f - e.w * e.w)) <= 1e-3f * (1.0f + k2 * e.w * e.w));
    c->ellipse_count += e.w < 1.0f;
    /* The invariants ic_cache_insert_batch holds a record to: a positive harmonic-mean distance and a
     * footprint of at least 0 (ic_cache_get_record hands them out). */
    return f[3] > 0.0f && f[7] > 0.0f && fabsf(nl - 1.0f) < 1e-3f && squeeze_ok && cd->harmonic_mean_dist > 0.0f &&
           cd->pixel_footprint >= 0.0f;
}

/* ---- settings text (cache.h: SETTINGS TEXT) ------------------------------------------------------ */

typedef struct setting {
    const char *key, *value;
    size_t key_len, value_len;
} setting;

/* The line of a well-formed text (len bytes) at *at, which moves past it; 0 past the last line. */
static int next_setting(const char *text, size_t len, size_t *at, setting *out)
{
    if (*at >= len)
        return 0;
    const char *line = text + *at, *end = memchr(line, '\n', len - *at), *eq = memchr(line, '=', (size_t)(end - line));
    *out = (setting){line, eq + 1, (size_t)(eq - line), (size_t)(end - eq - 1)};
    *at = (size_t)(end - text) + 1;
    return 1;
}

/* The first line of text whose key is key (key_len bytes), or 0. */
static int find_setting(const char *text, size_t len, const char *key, size_t key_len, setting *out)
{
    size_t at = 0;
    while (next_setting(text, len, &at, out))
        if (out->key_len == key_len && memcmp(out->key, key, key_len) == 0)
            return 1;
    return 0;
}

/* What is wrong with a settings text of len bytes (said after "the settings text"), or NULL. Every byte
 * read lies below len. A key given twice would make a text differ from itself (the comparison takes each
 * key's first line): a filter of the keys' hashes sends only a possible repeat to a look-up among the lines
 * before it, so a long text of distinct keys costs about one pass. */
static const char *settings_problem(const unsigned char *t, size_t len)
{
    if (len > IC_CACHE_MAX_SETTINGS_BYTES)
        return "is longer than IC_CACHE_MAX_SETTINGS_BYTES";
    if (len && t[len - 1] != '\n')
        return "does not end its last line";
    unsigned char seen[8192] = {0}; /* one bit per 16-bit hash of a key met */
    size_t line = 0;                /* where the current line starts */
    int has_key = 0;
    for (size_t k = 0; k < len;) {
        unsigned char c = t[k];
        if (c == '\n') {
            if (!has_key)
                return "has a line that is not key=value";
            line = ++k;
            has_key = 0;
            continue;
        }
        if (c == '=' && !has_key) {
            if (k == line)
                return "has a line with an empty key";
            has_key = 1;
            /* The lines before this one are whole and well-formed: find_setting may read them. */
            unsigned bit = (unsigned)ic_fnv1a64(IC_FNV64_OFFSET, t + line, k - line) & 0xffffu;
            setting before;
            if (seen[bit >> 3] & (1u << (bit & 7)) &&
                find_setting((const char *)t, line, (const char *)t + line, k - line, &before))
                return "gives a key twice";
            seen[bit >> 3] |= (unsigned char)(1u << (bit & 7));
        }
        if (c == '\r')
            return "holds a carriage return (end each line with \\n alone)";
        if (c < 0x20 || c == 0x7f)
            return "holds a control character";
        size_t n = ic_utf8_sequence(t + k, len - k);
        if (!n)
            return "is not well-formed UTF-8";
        k += n;
    }
    return NULL;
}

static int has_key(const setting *s, const char *key)
{
    return s->key_len == strlen(key) && memcmp(s->key, key, s->key_len) == 0;
}

/* How many leading bytes a and b share. */
static size_t common_prefix(const char *a, size_t a_len, const char *b, size_t b_len)
{
    size_t n = 0;
    while (n < a_len && n < b_len && a[n] == b[n])
        ++n;
    return n;
}

/* The len bytes at s as a message quotes them (out: QUOTE_BYTES): whole up to SAID_BYTES, else SAID_BYTES of
 * them around byte `from` (where two values part; len: the end, where a path names its file), "..." where
 * cut, and cut only between characters. */
#define QUOTE_BYTES (SAID_BYTES + 7)
static const char *quote(const char *s, size_t len, size_t from, char out[QUOTE_BYTES])
{
    size_t start = 0, end = len;
    if (len > SAID_BYTES) {
        start = from > SAID_BYTES / 2 ? from - SAID_BYTES / 2 : 0;
        if (start > len - SAID_BYTES)
            start = len - SAID_BYTES;
        while (start < len && ((unsigned char)s[start] & 0xC0) == 0x80)
            ++start;
        end = start + SAID_BYTES < len ? start + SAID_BYTES : len;
        while (end < len && end > start && ((unsigned char)s[end] & 0xC0) == 0x80)
            --end;
    }
    snprintf(out, QUOTE_BYTES, "%s%.*s%s", start ? "..." : "", (int)(end - start), s + start, end < len ? "..." : "");
    return out;
}

/* An option as the user gives it: "--rays 800", a flag (empty value) alone; its value quoted around from. */
static const char *say_option(const setting *s, size_t from, char out[2 * QUOTE_BYTES])
{
    char key[QUOTE_BYTES], value[QUOTE_BYTES];
    snprintf(out, 2 * QUOTE_BYTES, "%s%s%s", quote(s->key, s->key_len, 0, key), s->value_len ? " " : "",
             quote(s->value, s->value_len, from, value));
    return out;
}

/* The refusal for one setting: the file's (made, NULL if it has none) against this run's (now, NULL if
 * none). file and run: the two texts, for the scene's name. */
static ic_result say_difference(const char *path, const setting *made, const setting *now, const char *file,
                                size_t file_len, const char *run, size_t run_len, ic_error *err)
{
    const setting *k = made ? made : now;
    /* Both values are quoted from where they part. */
    const size_t from = made && now ? common_prefix(made->value, made->value_len, now->value, now->value_len) : 0;
    char key[QUOTE_BYTES], was[2 * QUOTE_BYTES], is[2 * QUOTE_BYTES];
    if (has_key(k, SCENE_KEY)) {
        setting fs, rs;
        const size_t nk = strlen(SCENE_NAME_KEY);
        int has_file = find_setting(file, file_len, SCENE_NAME_KEY, nk, &fs),
            has_run = find_setting(run, run_len, SCENE_NAME_KEY, nk, &rs);
        if (has_file && has_run && (fs.value_len != rs.value_len || memcmp(fs.value, rs.value, fs.value_len))) {
            const size_t at = common_prefix(fs.value, fs.value_len, rs.value, rs.value_len);
            return ic_error_set(err, IC_ERR_MISMATCH, "%s: made for another scene (saved for %s, this run's is %s); "
                                "render the scene it was made for, " REBUILD_INSTEAD, path,
                                quote(fs.value, fs.value_len, at, was), quote(rs.value, rs.value_len, at, is));
        }
        const setting *name = has_run ? &rs : has_file ? &fs : NULL;
        return ic_error_set(err, IC_ERR_MISMATCH, "%s: made for another scene (%s%s changed since the cache was "
                            "saved); render the scene as it was, " REBUILD_INSTEAD, path,
                            name ? quote(name->value, name->value_len, name->value_len, was) : "the scene",
                            name ? ", or a file it names," : "");
    }
    if (k->key_len > 2 && memcmp(k->key, "--", 2) == 0) {
        if (made)
            say_option(made, from, was);
        if (now)
            say_option(now, from, is);
        if (made && now)
            return ic_error_set(err, IC_ERR_MISMATCH, "%s: made with %s, this run has %s; rerun with %s, "
                                REBUILD_INSTEAD, path, was, is, was);
        if (made)
            return ic_error_set(err, IC_ERR_MISMATCH, "%s: made with %s, which this run does not give; rerun "
                                "with %s, " REBUILD_INSTEAD, path, was, was);
        quote(k->key, k->key_len, 0, key);
        return ic_error_set(err, IC_ERR_MISMATCH, "%s: made without %s, this run has %s; rerun without %s, "
                            REBUILD_INSTEAD, path, key, is, key);
    }
    return ic_error_set(err, IC_ERR_MISMATCH, "%s: made with %s: %s, this run's: %s; use the settings it "
                        "was made with, " REBUILD_INSTEAD, path, quote(k->key, k->key_len, 0, key),
                        made ? quote(made->value, made->value_len, from, was) : "none",
                        now ? quote(now->value, now->value_len, from, is) : "none");
}

/* After the hashes differ: the first setting of the file's text (in its order), then of this run's, that
 * the other lacks or gives another value, said in *err (IC_ERR_MISMATCH); IC_OK when a text is empty or
 * they agree, for the hashes to say it. */
static ic_result check_settings(const char *path, const char *file, size_t file_len, const char *run,
                                size_t run_len, ic_error *err)
{
    if (!file_len || !run_len)
        return IC_OK;
    setting a, b;
    size_t at = 0;
    while (next_setting(file, file_len, &at, &a)) {
        if (has_key(&a, SCENE_NAME_KEY))
            continue;
        int has = find_setting(run, run_len, a.key, a.key_len, &b);
        if (!has || b.value_len != a.value_len || memcmp(a.value, b.value, a.value_len) != 0)
            return say_difference(path, &a, has ? &b : NULL, file, file_len, run, run_len, err);
    }
    for (at = 0; next_setting(run, run_len, &at, &b);)
        if (!has_key(&b, SCENE_NAME_KEY) && !find_setting(file, file_len, b.key, b.key_len, &a))
            return say_difference(path, NULL, &b, file, file_len, run, run_len, err);
    return IC_OK;
}

/* ---- save ------------------------------------------------------------------------------------- */

typedef struct writer {
    FILE *fp;
    uint64_t hash;
    size_t len;
    unsigned char buf[1 << 16];
} writer;

static void w_flush(writer *w)
{
    /* A short write sets the stream's error flag; ic_atomic_file_commit checks it. */
    if (w->len)
        (void)fwrite(w->buf, 1, w->len, w->fp);
    w->len = 0;
}

static void w_bytes(writer *w, const unsigned char *b, size_t n)
{
    w->hash = ic_fnv1a64(w->hash, b, n);
    if (w->len + n > sizeof w->buf)
        w_flush(w);
    if (n > sizeof w->buf) {
        (void)fwrite(b, 1, n, w->fp);
        return;
    }
    memcpy(w->buf + w->len, b, n);
    w->len += n;
}

/* The payload section: the total, every record's length, then the floats in record order. */
static void write_payloads(writer *w, const ic_cache *c)
{
    uint64_t total = 0;
    for (uint32_t i = 0; i < c->count; ++i) {
        uint32_t n;
        ic_cache_payload(c, i, &n);
        total += n;
    }
    unsigned char b[8];
    put_u64(b, total);
    w_bytes(w, b, 8);
    for (uint32_t i = 0; i < c->count; ++i) {
        uint32_t n;
        ic_cache_payload(c, i, &n);
        put_u32(b, n);
        w_bytes(w, b, 4);
    }
    for (uint32_t i = 0; i < c->count; ++i) {
        uint32_t n;
        const float *f = ic_cache_payload(c, i, &n);
        for (uint32_t k = 0; k < n; ++k) {
            put_f32(b, f[k]);
            w_bytes(w, b, 4);
        }
    }
}

ic_result ic_cache_save(const ic_cache *c, const char *path, uint64_t scene_hash, ic_error *err)
{
    return ic_cache_save_with_settings(c, path, scene_hash, NULL, err);
}

/* A caller's settings text, checked as a file's is: IC_ERR_INVALID_ARG naming what is wrong. */
static ic_result check_caller_settings(const char *settings, const char *what, ic_error *err)
{
    const char *problem = settings_problem((const unsigned char *)settings, strlen(settings));
    return problem ? ic_error_set(err, IC_ERR_INVALID_ARG, "%s: the settings text %s; give lines key=value, each "
                                  "key once, each line ended by a line break (irrcache/cache.h: SETTINGS TEXT)", what, problem)
                   : IC_OK;
}

ic_result ic_cache_save_with_settings(const ic_cache *c, const char *path, uint64_t scene_hash,
                                      const char *settings, ic_error *err)
{
    if (!c || !path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no cache or no path to save to");
    if (!settings)
        settings = "";
    ic_result rc = check_caller_settings(settings, path, err);
    if (rc != IC_OK)
        return rc;
    ic_atomic_file f;
    rc = ic_atomic_file_open(&f, path, err);
    if (rc != IC_OK)
        return rc;
    writer *w = malloc(sizeof *w);
    if (!w) {
        ic_atomic_file_abort(&f);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory while saving", path);
    }
    w->fp = f.fp;
    w->hash = IC_FNV64_OFFSET;
    w->len = 0;

    unsigned char head[HEADER_BYTES];
    memcpy(head, MAGIC, 8);
    put_u32(head + 8, IC_CACHE_FILE_VERSION);
    put_u32(head + 12, PARAM_BYTES);
    put_u64(head + 16, scene_hash);
    encode_params(&c->params, head + 24);
    put_u64(head + 24 + PARAM_BYTES, c->count);
    w_bytes(w, head, sizeof head);
    unsigned char len[4];
    put_u32(len, (uint32_t)strlen(settings));
    w_bytes(w, len, 4);
    w_bytes(w, (const unsigned char *)settings, strlen(settings));
    unsigned char rec[RECORD_BYTES];
    for (uint32_t i = 0; i < c->count; ++i) {
        encode_record(c, i, rec);
        w_bytes(w, rec, sizeof rec);
    }
    write_payloads(w, c);
    unsigned char tail[8];
    put_u64(tail, w->hash);
    w_bytes(w, tail, sizeof tail);
    w_flush(w);
    free(w);
    /* commit checks the stream for write errors and removes the temporary file on any failure. */
    return ic_atomic_file_commit(&f, err);
}

/* ---- load ------------------------------------------------------------------------------------- */

/* Reads the file whole, once fstat says it is a regular file of at most max_bytes (0: the default). */
static ic_result read_all(const char *path, uint64_t max_bytes, unsigned char **out, size_t *size, ic_error *err)
{
    char *data = NULL;
    ic_result rc = ic_read_regular_file(path, "cache file", max_bytes ? max_bytes : IC_DEFAULT_MAX_CACHE_FILE_BYTES,
                                        "raise the limit with --max-cache-bytes (max_file_bytes of ic_cache_params) "
                                        "if the cache is really this large, else " NOT_CACHE_HINT, &data, size, NULL,
                                        err);
    *out = (unsigned char *)data;
    return rc;
}

/* A field's value as a message says it: a number, a switch's on or off, a weight's name. */
static void say_value(int kind, uint32_t bits, char *out, size_t size)
{
    static const char *const switches[] = {"default", "on", "off"};
    static const char *const weights[] = {"ward", "tabellion", "error"};
    float f;
    memcpy(&f, &bits, 4);
    if (kind == FIELD_FLOAT)
        snprintf(out, size, "%g", (double)f);
    else if (kind == FIELD_SWITCH && bits < 3)
        snprintf(out, size, "%s", switches[bits]);
    else if (kind == FIELD_WEIGHT && bits < 3)
        snprintf(out, size, "%s", weights[bits]);
    else
        snprintf(out, size, "%u", bits);
}

static ic_result check_params(const char *path, const unsigned char *block, const ic_cache_params *p,
                              ic_error *err)
{
    param_field f[N_PARAM_FIELDS];
    param_fields(p, f);
    for (int k = 0; k < N_PARAM_FIELDS; ++k) {
        uint32_t have = get_u32(block + 4 * k), want;
        if (f[k].kind == FIELD_FLOAT)
            memcpy(&want, &f[k].f, 4);
        else
            want = f[k].u;
        if (have == want)
            continue;
        char in_file[32], now[32];
        say_value(f[k].kind, have, in_file, sizeof in_file);
        say_value(f[k].kind, want, now, sizeof now);
        return ic_error_set(err, IC_ERR_MISMATCH, "%s: made with other cache parameters (%s %s in the file, %s now); "
                            MISMATCH_HINT, path, f[k].name, in_file, now);
    }
    return IC_OK;
}

/* The payload section at b (past its total): lengths that add up to the total, finite floats. */
static ic_result read_payloads(ic_cache *c, const char *path, const unsigned char *b, uint64_t total, ic_error *err)
{
    const unsigned char *f = b + 4 * (size_t)c->count;
    uint64_t at = 0;
    float *buf = NULL;
    size_t buf_len = 0;
    ic_result rc = IC_OK;
    for (uint32_t i = 0; i < c->count && rc == IC_OK; ++i) {
        uint32_t n = get_u32(b + 4 * (size_t)i);
        if (n > total - at) {
            rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: record %u's payload runs past the file; " REBUILD_HINT, path,
                              i);
            break;
        }
        if (n > buf_len) {
            float *nb = realloc(buf, (size_t)n * sizeof *nb);
            if (!nb) {
                rc = ic_error_set(err, IC_ERR_OOM, "%s: out of memory for record %u's payload", path, i);
                break;
            }
            buf = nb;
            buf_len = n;
        }
        for (uint32_t k = 0; k < n; ++k)
            buf[k] = get_f32(f + 4 * (size_t)(at + k));
        at += n;
        if (n && ic_cache_set_payload(c, i, buf, n, NULL) != IC_OK)
            rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: record %u's payload is invalid; " REBUILD_HINT, path, i);
    }
    if (rc == IC_OK && at != total)
        rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: payload lengths do not add up; " REBUILD_HINT, path);
    free(buf);
    return rc;
}

ic_result ic_cache_read_file(const char *path, const ic_cache_params *params, void **data, size_t *size,
                             ic_error *err)
{
    if (!path || !data || !size)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no path or no output buffer");
    unsigned char *bytes = NULL;
    ic_result rc = read_all(path, params ? params->max_file_bytes : 0, &bytes, size, err);
    *data = bytes;
    return rc;
}

ic_result ic_cache_load(const char *path, const ic_cache_params *params, uint64_t scene_hash, ic_cache **out,
                        ic_error *err)
{
    return ic_cache_load_with_settings(path, params, scene_hash, NULL, out, err);
}

ic_result ic_cache_load_with_settings(const char *path, const ic_cache_params *params, uint64_t scene_hash,
                                      const char *settings, ic_cache **out, ic_error *err)
{
    if (!path || !out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no path or no output handle");
    *out = NULL;
    void *data = NULL;
    size_t size = 0;
    ic_result rc = ic_cache_read_file(path, params, &data, &size, err);
    if (rc == IC_OK)
        rc = ic_cache_load_memory_with_settings(path, data, size, params, scene_hash, settings, out, err);
    free(data);
    return rc;
}

ic_result ic_cache_load_memory(const char *path, const void *bytes, size_t size, const ic_cache_params *params,
                               uint64_t scene_hash, ic_cache **out, ic_error *err)
{
    return ic_cache_load_memory_with_settings(path, bytes, size, params, scene_hash, NULL, out, err);
}

ic_result ic_cache_load_memory_with_settings(const char *path, const void *bytes, size_t size,
                                             const ic_cache_params *params, uint64_t scene_hash,
                                             const char *settings, ic_cache **out, ic_error *err)
{
    if (!path || !out || (!bytes && size))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no name, no bytes or no output handle");
    *out = NULL;
    if (!settings)
        settings = "";
    ic_cache_params p;
    ic_result rc = check_caller_settings(settings, path, err);
    if (rc == IC_OK)
        rc = ic_cache_params_resolve(params, &p, err);
    if (rc != IC_OK)
        return rc;
    const unsigned char *data = bytes;

    if (size && memcmp(data, MAGIC, size < 8 ? size : 8) != 0) /* shorter than the magic: no cache file either */
        rc = ic_error_set(err, IC_ERR_PARSE, "%s: not an irrcache cache file; " NOT_CACHE_HINT, path);
    else if (size < HEADER_BYTES + 8)
        rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: truncated (%zu bytes); " REBUILD_HINT, path, size);
    else if (get_u32(data + 8) > IC_CACHE_FILE_VERSION)
        rc = ic_error_set(err, IC_ERR_MISMATCH, "%s: cache format version %u, newer than this build reads (%u to %u); "
                          "load it with the irrcache that wrote it, or build the cache again", path, get_u32(data + 8),
                          IC_CACHE_FILE_OLDEST, IC_CACHE_FILE_VERSION);
    else if (get_u32(data + 8) < IC_CACHE_FILE_OLDEST)
        rc = ic_error_set(err, IC_ERR_MISMATCH, "%s: cache format version %u, this build reads %u to %u; " REBUILD_HINT,
                          path, get_u32(data + 8), IC_CACHE_FILE_OLDEST, IC_CACHE_FILE_VERSION);
    else if (get_u32(data + 12) != PARAM_BYTES)
        rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: corrupt header; " REBUILD_HINT, path);
    if (rc != IC_OK)
        return rc;
    const uint32_t version = get_u32(data + 8);
    /* The settings text (version 4): its length bounded by the file's before anything past it is read. */
    const int has_settings = version >= 4;
    const uint64_t text_at = HEADER_BYTES + 4;
    uint64_t text_len = 0;
    if (has_settings && size < text_at + 8)
        return ic_error_set(err, IC_ERR_CORRUPT, "%s: truncated (%zu bytes); " REBUILD_HINT, path, size);
    if (has_settings)
        text_len = get_u32(data + HEADER_BYTES);
    if (has_settings && (text_len > IC_CACHE_MAX_SETTINGS_BYTES || text_len > size - text_at - 8))
        return ic_error_set(err, IC_ERR_CORRUPT, "%s: a settings text of %llu bytes, %s; " REBUILD_HINT, path,
                            (unsigned long long)text_len, text_len > IC_CACHE_MAX_SETTINGS_BYTES ?
                            "more than a cache file holds" : "past the end of the file");
    const uint64_t records_at = has_settings ? text_at + text_len : HEADER_BYTES;
    uint64_t count = get_u64(data + 24 + PARAM_BYTES);
    const int has_payloads = version >= 2, has_squeeze = version >= 3;
    const uint64_t rec_bytes = has_squeeze ? RECORD_BYTES : RECORD_BYTES_V2;
    const uint64_t per_record = rec_bytes + (has_payloads ? 4u : 0u), fixed = records_at + 8 + (has_payloads ? 8u : 0u);
    uint64_t max_count = size >= fixed ? (size - fixed) / per_record : 0, payload_floats = 0;
    if (has_payloads && count <= max_count)
        payload_floats = get_u64(data + records_at + count * rec_bytes);
    const char *problem = NULL;
    if (count > max_count || size < fixed ||
        payload_floats != (size - fixed - count * per_record) / 4 || size != fixed + count * per_record + 4 * payload_floats)
        rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: %s (%zu bytes for %llu records); " REBUILD_HINT, path,
                          count > max_count || size < fixed ? "truncated" : "wrong length", size, (unsigned long long)count);
    else if (ic_fnv1a64(IC_FNV64_OFFSET, data, size - 8) != get_u64(data + size - 8))
        rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: checksum mismatch, the file is corrupt; " REBUILD_HINT, path);
    else if ((problem = settings_problem(data + text_at, text_len)) != NULL)
        rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: the settings text %s; " REBUILD_HINT, path, problem);
    else if (get_u64(data + 16) != scene_hash) {
        /* Which setting differs, where both texts say; else the hashes alone. */
        rc = check_settings(path, (const char *)data + text_at, text_len, settings, strlen(settings), err);
        if (rc == IC_OK)
            rc = ic_error_set(err, IC_ERR_MISMATCH,
                              "%s: made for another scene or settings that change its records (hash %016llx, here "
                              "%016llx%s); " MISMATCH_HINT, path, (unsigned long long)get_u64(data + 16),
                              (unsigned long long)scene_hash,
                              !text_len ? "; the file keeps no settings to say which"
                              : !*settings ? "; this run gives no settings to compare with the file's"
                                           : "; the settings it keeps agree with this run's");
    } else if (count >= UINT32_MAX)
        rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: too many records", path);
    else
        rc = check_params(path, data + 24, &p, err);
    if (rc != IC_OK)
        return rc;

    ic_cache *c = NULL;
    rc = ic_cache_create(&p, &c, err);
    if (rc == IC_OK && ic_cache_reserve(c, (uint32_t)count) != IC_OK)
        rc = ic_error_set(err, IC_ERR_OOM, "%s: out of memory for %llu records", path, (unsigned long long)count);
    for (uint32_t i = 0; rc == IC_OK && i < count; ++i) {
        if (!decode_record(c, i, data + records_at + (size_t)i * rec_bytes, has_squeeze)) {
            rc = ic_error_set(err, IC_ERR_CORRUPT, "%s: record %u is invalid; " REBUILD_HINT, path, i);
            break;
        }
        /* A checksum proves only that the file is as written: the values must also fit the octree. */
        ic_octree_items sph = ic_cache_tree_items(c);
        const ic_float4 *s = &c->sphere[i];
        if (!ic_cache_sphere_in_range(s, ic_octree_item_radius(&sph, i)))
            rc = ic_error_set(err, IC_ERR_CORRUPT,
                              "%s: record %u at (%g, %g, %g) with radius %g lies beyond %g, the largest coordinate "
                              "a cache holds; the file is corrupt: " REBUILD_HINT, path, i, (double)s->x,
                              (double)s->y, (double)s->z, (double)s->w, IC_CACHE_MAX_COORD);
    }
    if (rc == IC_OK) {
        c->count = (uint32_t)count;
        if (has_payloads)
            rc = read_payloads(c, path, data + records_at + count * rec_bytes + 8, payload_floats, err);
    }
    if (rc == IC_OK) {
        ic_octree_items pts = ic_cache_point_items(c), sph = ic_cache_tree_items(c);
        if (ic_octree_build(&c->points, &pts, c->count) != IC_OK || ic_octree_build(&c->tree, &sph, c->count) != IC_OK)
            rc = ic_error_set(err, IC_ERR_OOM, "%s: out of memory building the octree", path);
        /* Loaded caches serve final renders: freeze, as ic_cache_rebuild_index does. */
        if (rc == IC_OK && c->params.freeze == IC_CACHE_ON && ic_cache_freeze(c, NULL) != IC_OK)
            rc = ic_error_set(err, IC_ERR_OOM, "%s: out of memory freezing the look-up layout", path);
    }
    if (rc != IC_OK) {
        ic_cache_destroy(c);
        return rc;
    }
    *out = c;
    return IC_OK;
}
