/*
 * cache_only.c — the irradiance cache on its own (irrcache/cache.h): a cache made from records this
 * program supplies, then queried between them. A renderer, light-map baker or engine would fill the
 * records from its own hemisphere sampling (or through irrcache/gather.h with its own ray tracer).
 *
 *   cache_only        prints the interpolated irradiance at a point among four records
 */
#include <irrcache/cache.h>
#include <irrcache/version.h>

#include <stdio.h>

int main(void)
{
    ic_error err;
    ic_cache_params params = {0}; /* zero means default in every field */
    params.accuracy = 0.3f;
    ic_cache *cache = NULL;
    if (ic_cache_create(&params, &cache, &err) != IC_OK) {
        fprintf(stderr, "cache_only: %s\n", err.message);
        return 1;
    }

    /* Four records on the floor (y = 0, normal +y), a metre apart, irradiance rising along x. */
    for (int i = 0; i < 4; ++i) {
        ic_record r = {0};
        r.position = (ic_vec3){(float)(i % 2), 0.0f, (float)(i / 2)};
        r.normal = (ic_vec3){0.0f, 1.0f, 0.0f};
        r.tangent = (ic_vec3){1.0f, 0.0f, 0.0f};
        float e = 1.0f + 0.5f * (float)(i % 2);
        r.irradiance = (ic_vec3){e, e, e};
        r.harmonic_mean_dist = 4.0f; /* distance to the surroundings: sets the record's radius */
        if (ic_cache_insert(cache, &r, NULL, &err) != IC_OK) {
            fprintf(stderr, "cache_only: %s\n", err.message);
            ic_cache_destroy(cache);
            return 1;
        }
    }

    /* A look-up in the middle: every record contributes; the estimate is their weighted mean. */
    ic_cache_lookup q = ic_cache_lookup_at((ic_vec3){0.5f, 0.0f, 0.5f}, (ic_vec3){0.0f, 1.0f, 0.0f},
                                           IC_ACCEPT_CONSTRUCTION);
    ic_cache_estimate est;
    int covered = ic_cache_query(cache, &q, &est);
    printf("irrcache %s (headers %s): %u records\n", ic_version(), IRRCACHE_VERSION_STRING,
           ic_cache_count(cache));
    printf("at (0.5, 0, 0.5): %s, E = (%.3f, %.3f, %.3f) from %u records\n",
           covered ? "covered" : "not covered", est.irradiance.x, est.irradiance.y, est.irradiance.z,
           est.contributor_count);
    ic_cache_destroy(cache);
    return covered && est.contributor_count == 4 ? 0 : 1;
}
