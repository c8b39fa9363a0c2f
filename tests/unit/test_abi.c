/*
 * test_abi.c — the sizes of the public structs (include/irrcache/) on 64-bit Linux, for the version that
 * declares them. A program built against one release's headers hands these structs to the library, so a
 * struct that grows or shrinks within a release corrupts memory (ic_render_stats went from 2,048 to 21,432
 * bytes with 0.2.0 still set). When a size here changes, bump IRRCACHE_VERSION_MINOR (and project(VERSION)
 * in CMakeLists.txt: the shared libraries' SONAME follows the minor version while it is 0.x) and update
 * the table for the new version.
 */
#include "irrcache/cache.h"
#include "irrcache/comm.h"
#include "irrcache/gather.h"
#include "irrcache/image.h"
#include "irrcache/points.h"
#include "irrcache/render.h"
#include "irrcache/version.h"
#include "test_util.h"

#include <stdint.h>
#include <stdio.h>

int main(void)
{
#if UINTPTR_MAX == 0xffffffffffffffffu && defined(__linux__)
    static const struct {
        const char *name;
        size_t size, expected;
    } structs[] = {
        {"ic_scene_load_options", sizeof(ic_scene_load_options), 56},
        {"ic_ic_options", sizeof(ic_ic_options), 304},
        {"ic_record_view", sizeof(ic_record_view), 56},
        {"ic_render_aovs", sizeof(ic_render_aovs), 120},
        {"ic_render_progress", sizeof(ic_render_progress), 32},
        {"ic_render_checkpoint", sizeof(ic_render_checkpoint), 40},
        {"ic_render_options", sizeof(ic_render_options), 432},
        {"ic_render_stats", sizeof(ic_render_stats), 21432},
        {"ic_image", sizeof(ic_image), 16},
        {"ic_image_layer", sizeof(ic_image_layer), 16},
        {"ic_image_meta", sizeof(ic_image_meta), 16},
        {"ic_image_write_options", sizeof(ic_image_write_options), 40},
        {"ic_falsecolor_options", sizeof(ic_falsecolor_options), 24},
        {"ic_image_metrics", sizeof(ic_image_metrics), 56},
        {"ic_cache_params", sizeof(ic_cache_params), 88},
        {"ic_record", sizeof(ic_record), 172},
        {"ic_cache_contribution", sizeof(ic_cache_contribution), 20},
        {"ic_cache_lookup", sizeof(ic_cache_lookup), 56},
        {"ic_cache_estimate", sizeof(ic_cache_estimate), 28},
        {"ic_cache_index_stats", sizeof(ic_cache_index_stats), 80},
        {"ic_gather_opts", sizeof(ic_gather_opts), 56},
        {"ic_gather_point", sizeof(ic_gather_point), 32},
        {"ic_gather_result", sizeof(ic_gather_result), 180},
        {"ic_gather_extent_opts", sizeof(ic_gather_extent_opts), 16},
        {"ic_gather_extent", sizeof(ic_gather_extent), 44},
        {"ic_gather_radiance_result", sizeof(ic_gather_radiance_result), 104},
        {"ic_sensor_point", sizeof(ic_sensor_point), 24},
        {"ic_points_options", sizeof(ic_points_options), 368},
        {"ic_point_result", sizeof(ic_point_result), 40},
        {"ic_points_stats", sizeof(ic_points_stats), 32},
        {"ic_points_grid_spec", sizeof(ic_points_grid_spec), 40},
        {"ic_comm", sizeof(ic_comm), 88},
    };
    const int same_version = IRRCACHE_VERSION_NUMBER == IRRCACHE_MAKE_VERSION(0, 5, 0);
    CHECK(same_version, "the table below is 0.5.0's; version.h says %s: update it for the new version",
          IRRCACHE_VERSION_STRING);
    for (size_t i = 0; same_version && i < sizeof structs / sizeof structs[0]; ++i)
        CHECK(structs[i].size == structs[i].expected,
              "%s is %zu bytes, %zu in 0.5.0: a public struct changed within a release; bump the minor version "
              "and update this table", structs[i].name, structs[i].size, structs[i].expected);
#else
    printf("not a 64-bit Linux build: the sizes are not checked\n");
#endif
    TEST_MAIN_END();
}
