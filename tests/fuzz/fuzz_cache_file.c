/*
 * fuzz_cache_file.c — ic_cache_load of a cache file (layout: src/cache/cache_file.c).
 *
 * A mutated file would almost never pass the loader's checks before record decoding, so the harness
 * "re-signs" every input of at least a header's length first, by the layout of the version its header
 * names: version 1, the record count from the length (a partial last record cut off); versions 2 to 4
 * (records of 156 and 172 bytes, then the payload section: a float total, a length per record, the
 * floats), the header's count kept where the length holds that many records and their lengths (else the
 * most it holds), the float total from the bytes left, and the records' lengths, in order, cut so that
 * they add up to it (the last one takes the rest); version 4's settings text keeps its bytes, its length
 * cut to what the file holds. Then the trailing FNV-1a 64 checksum is recomputed, and the scene hash and
 * the cache parameters the load asks for are those the file's header holds. Magic, version, parameter
 * values, record fields, the settings text and payload contents stay as mutated, so their checks are
 * fuzzed too. A loaded cache is then looked up at each of its first records, which reads the octree and
 * the frozen layout built from the file's values; and the file is loaded again for another hash with a
 * settings text of its own, which compares the two texts (cache.h: SETTINGS TEXT), and once more for
 * another hash with the file's own text, which must never be said to differ from itself.
 */
#include "fuzz_util.h"

#include "irrcache/cache.h"

#define HEADER_BYTES 88u
#define PARAM_OFFSET 24u
#define COUNT_OFFSET 80u
#define VERSION_OFFSET 8u
#define RECORD_BYTES_V1 156u /* versions 1 and 2 */
#define RECORD_BYTES_V3 172u
#define MAX_QUERIES 64u
#define SETTINGS_MAX IC_CACHE_MAX_SETTINGS_BYTES
/* The text of the second load: what irrcache's renderer writes, with values no file is likely to hold. */
#define RUN_SETTINGS "scene=0000000000000000\nscene file=fuzz.json\n--strategy=lazy\n--rays=52 (4 x 13 strata)\n" \
                     "--no-gradients=\nemitters=none\n"

static uint32_t get_u32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}
static uint64_t get_u64(const unsigned char *b)
{
    return (uint64_t)get_u32(b) | (uint64_t)get_u32(b + 4) << 32;
}
static float get_f32(const unsigned char *b)
{
    uint32_t v = get_u32(b);
    float f;
    memcpy(&f, &v, 4);
    return f;
}
static void put_u32(unsigned char *b, uint32_t v)
{
    for (int k = 0; k < 4; ++k)
        b[k] = (unsigned char)(v >> (8 * k));
}
static void put_u64(unsigned char *b, uint64_t v)
{
    put_u32(b, (uint32_t)v);
    put_u32(b + 4, (uint32_t)(v >> 32));
}

/* Makes buf (size bytes, at least a header and a checksum) a consistent file of its version's layout;
 * returns its new size (never larger). */
static size_t resign(unsigned char *buf, size_t size)
{
    uint32_t version = get_u32(buf + VERSION_OFFSET);
    uint64_t records_at = HEADER_BYTES; /* version 4: past the settings text */
    if (version == 4) {
        if (size < HEADER_BYTES + 4 + 8 + 8)
            return size; /* no room for the text's length and the payload total: the loader says "truncated" */
        /* Room for the text that leaves the payload total and the checksum, so a cut text is still read. */
        uint64_t text = get_u32(buf + HEADER_BYTES), room = size - HEADER_BYTES - 4 - 8 - 8;
        if (text > room && text <= SETTINGS_MAX)
            text = room; /* a length over the limit stays, for the loader to refuse */
        if (text > room)
            return size;
        put_u32(buf + HEADER_BYTES, (uint32_t)text);
        records_at = HEADER_BYTES + 4 + text;
    }
    uint64_t body = size - records_at - 8;
    if (version < 2 || version > 4) {
        uint64_t count = body / RECORD_BYTES_V1;
        put_u64(buf + COUNT_OFFSET, count);
        size = records_at + 8 + count * RECORD_BYTES_V1;
    } else {
        uint64_t rec = version >= 3 ? RECORD_BYTES_V3 : RECORD_BYTES_V1;
        uint64_t most = body >= 8 ? (body - 8) / (rec + 4) : 0, count = get_u64(buf + COUNT_OFFSET);
        if (body < 8)
            return size; /* no room for the payload total: the loader says "truncated" */
        if (count > most)
            count = most;
        uint64_t floats = (body - 8 - count * (rec + 4)) / 4, left = floats;
        unsigned char *lengths = buf + records_at + count * rec + 8;
        for (uint64_t i = 0; i < count; ++i) {
            uint64_t n = i + 1 == count ? left : get_u32(lengths + 4 * i);
            n = n < left ? n : left;
            put_u32(lengths + 4 * i, (uint32_t)n);
            left -= n;
        }
        if (count == 0)
            floats = 0;
        put_u64(buf + COUNT_OFFSET, count);
        put_u64(buf + records_at + count * rec, floats);
        size = records_at + count * rec + 8 + 4 * count + 4 * floats + 8;
    }
    put_u64(buf + size - 8, ic_fnv1a64(IC_FNV64_OFFSET, buf, size - 8));
    return size;
}

/* The parameter block, in file order (cache_file.c: param_fields). */
static void decode_params(const unsigned char *b, ic_cache_params *p)
{
    memset(p, 0, sizeof *p);
    p->weight = (ic_weight_kind)(int)get_u32(b);
    p->accuracy = get_f32(b + 4);
    p->min_radius = get_f32(b + 8);
    p->max_radius = get_f32(b + 12);
    p->min_radius_pixels = get_f32(b + 16);
    p->max_radius_pixels = get_f32(b + 20);
    p->gradient_clamp = (ic_cache_switch)(int)get_u32(b + 24);
    p->neighbor_clamp = (ic_cache_switch)(int)get_u32(b + 28);
    p->validity_clamp = (ic_cache_switch)(int)get_u32(b + 32);
    p->validity_k = get_u32(b + 36);
    p->validity_angle_deg = get_f32(b + 40);
    p->gradient_difference = (ic_cache_switch)(int)get_u32(b + 44);
    p->gradient_difference_threshold = get_f32(b + 48);
    p->threads = 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ic_cache_params params;
    memset(&params, 0, sizeof params);
    params.threads = 1;
    uint64_t scene_hash = 0;
    unsigned char *buf = malloc(size ? size : 1);
    if (!buf)
        return 0;
    if (size)
        memcpy(buf, data, size);
    if (size >= HEADER_BYTES + 8) {
        size = resign(buf, size);
        scene_hash = get_u64(buf + 16);
        decode_params(buf + PARAM_OFFSET, &params);
    }
    /* The file's own settings text (version 4, within the file, no NUL), for the third load below. */
    char *own = NULL;
    if (size >= HEADER_BYTES + 4 + 8 && get_u32(buf + VERSION_OFFSET) == 4) {
        uint64_t text = get_u32(buf + HEADER_BYTES);
        if (text <= size - HEADER_BYTES - 4 - 8 && !memchr(buf + HEADER_BYTES + 4, 0, (size_t)text) &&
            (own = malloc((size_t)text + 1)) != NULL) {
            memcpy(own, buf + HEADER_BYTES + 4, (size_t)text);
            own[text] = '\0';
        }
    }
    char path[1024];
    fuzz_write("cache.irc", buf, size, path, sizeof path);
    free(buf);

    ic_cache *cache = NULL;
    ic_error err;
    int ok = ic_cache_load(path, &params, scene_hash, &cache, &err) == IC_OK;
    fuzz_report(ok, err.message);
    if (ok) {
        uint32_t n = ic_cache_count(cache);
        for (uint32_t i = 0; i < n && i < MAX_QUERIES; ++i) {
            ic_record r;
            if (ic_cache_get_record(cache, i, &r) != IC_OK)
                continue;
            ic_cache_contribution contrib[8];
            ic_cache_lookup q;
            memset(&q, 0, sizeof q);
            q.position = r.position;
            q.normal = r.normal;
            q.acceptance = (i & 1) ? IC_ACCEPT_FINAL : IC_ACCEPT_CONSTRUCTION;
            q.bounce = r.bounce;
            q.contributions = contrib;
            q.contribution_capacity = 8;
            ic_cache_estimate est;
            (void)ic_cache_query(cache, &q, &est);
            uint32_t idx[8];
            float d2[8];
            (void)ic_cache_knn(cache, r.position, 8, idx, d2);
        }
    }
    ic_cache_destroy(cache);
    cache = NULL;
    if (ic_cache_load_with_settings(path, &params, scene_hash ^ 1, RUN_SETTINGS, &cache, &err) == IC_OK)
        abort(); /* a file is never taken for another hash */
    ic_cache_destroy(cache);
    cache = NULL;
    /* A text never differs from itself: refused for another hash with the file's own text, the message
     * names no setting (the texts agree), or the text is refused as damaged. */
    if (own && *own) {
        ic_result rc = ic_cache_load_with_settings(path, &params, scene_hash ^ 1, own, &cache, &err);
        if (rc == IC_OK || (rc == IC_ERR_MISMATCH && !strstr(err.message, "the settings it keeps agree with this run's")))
            abort();
        ic_cache_destroy(cache);
    }
    free(own);
    return 0;
}
