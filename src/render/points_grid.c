/*
 * points_grid.c — ic_points_grid (irrcache/points.h): the sensors of a horizontal work-plane grid, one at
 * the centre of each whole cell that fits in the floor area, the grid centred in it so that the margins
 * to opposite walls are equal.
 */
#include "irrcache/points.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

/* Whole cells of side s along [lo, hi]: at least 1 when the side is at least one cell long. A side that is
 * a whole number of cells as the user wrote it must not lose one to rounding: the corners are floats (0.7
 * is stored as 0.69999999, seven cells of 0.1 less 1.2e-8; it once made a 0.7 m side at 0.1 m six cells),
 * so the side is lengthened by the most their rounding can have taken (half an ulp each, at most
 * 2^-24 |corner|; twice that here), and the 1e-9 covers the division's own rounding (4 m at 1 m). */
static double cells_along(float lo, float hi, double s)
{
    double slack = FLT_EPSILON * (fabs((double)lo) + fabs((double)hi));
    return floor(((double)hi - (double)lo + slack) / s + 1e-9);
}

ic_result ic_points_grid(const ic_points_grid_spec *g, ic_sensor_point **out, uint32_t *cols, uint32_t *rows,
                         ic_error *err)
{
    if (!g || !out || !cols || !rows)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "grid: NULL spec or result");
    *out = NULL;
    *cols = *rows = 0;
    if (!(g->spacing > 0.0) || !isfinite(g->spacing))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "grid: spacing %g must be > 0", g->spacing);
    if (!(g->height >= 0.0) || !isfinite(g->height))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "grid: height %g must be >= 0", g->height);
    double x0 = g->lo.x, x1 = g->hi.x, z0 = g->lo.z, z1 = g->hi.z, y = (double)g->lo.y + g->height;
    if (!(x1 > x0) || !(z1 > z0) || !(g->hi.y >= g->lo.y) || !isfinite(x1 - x0) || !isfinite(z1 - z0))
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "grid: the box (%g %g %g) - (%g %g %g) is empty; give x0 < x1, y0 <= y1, z0 < z1",
                            (double)g->lo.x, (double)g->lo.y, (double)g->lo.z, (double)g->hi.x, (double)g->hi.y,
                            (double)g->hi.z);
    /* Compared as stored: the sensors' height is a float, as is the box's top (y0 0 and 1.9 m, the box's
     * 1.9 stored as 1.89999998, were once refused as "1.9 lies above 1.9"). */
    if ((float)y > g->hi.y)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "grid: the plane at y0 + height = %g lies above the box's top "
                            "%g; give a height of at most %g, or a taller box", y, (double)g->hi.y,
                            (double)g->hi.y - (double)g->lo.y);
    double nx = cells_along(g->lo.x, g->hi.x, g->spacing), nz = cells_along(g->lo.z, g->hi.z, g->spacing);
    if (nx < 1.0 || nz < 1.0)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "grid: no whole %g cell fits in %g x %g; give a smaller spacing", g->spacing, x1 - x0,
                            z1 - z0);
    if (nx * nz > (double)IC_MAX_GRID_POINTS)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "grid: %g x %g points is more than %u; give a larger spacing",
                            nx, nz, IC_MAX_GRID_POINTS);
    uint32_t c = (uint32_t)nx, r = (uint32_t)nz;
    ic_sensor_point *p = malloc(sizeof *p * (size_t)c * r);
    if (!p)
        return ic_error_set(err, IC_ERR_OOM, "grid: out of memory for %u points", c * r);
    /* the first centre, half a cell plus half the leftover length from the side */
    double fx = x0 + 0.5 * ((x1 - x0) - (nx - 1.0) * g->spacing), fz = z0 + 0.5 * ((z1 - z0) - (nz - 1.0) * g->spacing);
    for (uint32_t j = 0; j < r; ++j)
        for (uint32_t i = 0; i < c; ++i) {
            ic_sensor_point *s = &p[(size_t)j * c + i];
            s->position = (ic_vec3){(float)(fx + i * g->spacing), (float)y, (float)(fz + j * g->spacing)};
            s->normal = (ic_vec3){0.0f, 1.0f, 0.0f};
        }
    *out = p;
    *cols = c;
    *rows = r;
    return IC_OK;
}
