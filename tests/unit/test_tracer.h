/*
 * test_tracer.h — a scene loaded with its accelerator and a path tracer over it, for the tests that drive the
 * integrators' internals (ic_ctx) directly.
 */
#ifndef IC_TEST_TRACER_H
#define IC_TEST_TRACER_H

#include "integrators/ic_internal.h"

#include <string.h>

/* Loads path into *scene and *accel and fills *tr (max_depth 0: the default). 0 with err set on failure. */
static inline int test_tracer_load(const char *path, int max_depth, ic_scene **scene, ic_accel **accel, ic_tracer *tr,
                                   ic_error *err)
{
    ic_scene_load_options lo = {0};
    *scene = NULL;
    *accel = NULL;
    if (ic_scene_load(path, &lo, scene, err) != IC_OK || ic_accel_create(*scene, accel, err) != IC_OK)
        return 0;
    memset(tr, 0, sizeof *tr);
    tr->scene = *scene;
    tr->accel = *accel;
    tr->pt.max_depth = max_depth;
    tr->pt = ic_pt_params_resolve(tr->pt);
    return 1;
}

#endif
