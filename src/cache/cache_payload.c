/*
 * cache_payload.c — floats attached to records beyond their irradiance (cache.h: ic_cache_set_payload):
 * one growing arena of floats and, per record, where its payload starts and how long it is.
 */
#include "cache_store.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void ic_cache_payload_free(ic_cache *c)
{
    free(c->payload_at);
    free(c->payload_len);
    free(c->payload);
    c->payload_at = NULL;
    c->payload_len = NULL;
    c->payload = NULL;
    c->payload_records = 0;
    c->payload_used = c->payload_cap = 0;
}

void ic_cache_payload_truncate(ic_cache *c, uint32_t first)
{
    for (uint32_t i = first; i < c->payload_records; ++i)
        c->payload_len[i] = 0;
}

/* Per-record entries for every record the cache has room for. */
static int grow_index(ic_cache *c)
{
    if (c->payload_records >= c->cap)
        return 1;
    uint64_t *at = realloc(c->payload_at, (size_t)c->cap * sizeof *at);
    if (!at)
        return 0;
    c->payload_at = at;
    uint32_t *len = realloc(c->payload_len, (size_t)c->cap * sizeof *len);
    if (!len)
        return 0;
    c->payload_len = len;
    memset(at + c->payload_records, 0, (size_t)(c->cap - c->payload_records) * sizeof *at);
    memset(len + c->payload_records, 0, (size_t)(c->cap - c->payload_records) * sizeof *len);
    c->payload_records = c->cap;
    return 1;
}

ic_result ic_cache_set_payload(ic_cache *c, uint32_t index, const float *data, uint32_t count, ic_error *err)
{
    if (!c || index >= c->count || (count && !data))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: payload for record %u of %u", index, c ? c->count : 0);
    for (uint32_t k = 0; k < count; ++k)
        if (!isfinite(data[k]))
            return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: payload of record %u has a non-finite value at %u",
                                index, k);
    if (!grow_index(c))
        return ic_error_set(err, IC_ERR_OOM, "cache: out of memory for payloads");
    if (count > c->payload_len[index] || c->payload_len[index] == 0) {
        /* A longer payload goes to the arena's end; a shorter one reuses its place. */
        if (c->payload_used + count > c->payload_cap) {
            size_t cap = c->payload_cap ? c->payload_cap : 4096;
            while (cap < c->payload_used + count)
                cap *= 2;
            float *p = realloc(c->payload, cap * sizeof *p);
            if (!p)
                return ic_error_set(err, IC_ERR_OOM, "cache: out of memory for payloads (%zu floats)", cap);
            c->payload = p;
            c->payload_cap = cap;
        }
        c->payload_at[index] = c->payload_used;
        c->payload_used += count;
    }
    if (count)
        memcpy(c->payload + c->payload_at[index], data, (size_t)count * sizeof *data);
    c->payload_len[index] = count;
    return IC_OK;
}

const float *ic_cache_payload(const ic_cache *c, uint32_t index, uint32_t *count)
{
    if (!c || index >= c->count || index >= c->payload_records || c->payload_len[index] == 0) {
        if (count)
            *count = 0;
        return NULL;
    }
    if (count)
        *count = c->payload_len[index];
    return c->payload + c->payload_at[index];
}

size_t ic_cache_payload_bytes(const ic_cache *c)
{
    if (!c)
        return 0;
    return c->payload_cap * sizeof(float) + (size_t)c->payload_records * (sizeof(uint64_t) + sizeof(uint32_t));
}
