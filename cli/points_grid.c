/*
 * points_grid.c — `irrcache points --grid`: reading the grid's box from the command line and writing the
 * false-colour map of its results (the map itself is drawn by ic_falsecolor_render, the grid made by
 * ic_points_grid).
 */
#include "points_grid.h"

#include "irrcache/image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int ic_cli_grid_box(int argc, char **argv, int *i, ic_points_grid_spec *spec)
{
    double v[6];
    for (int k = 0; k < 6; ++k) {
        char *end = NULL;
        const char *s = *i + 1 + k < argc ? argv[*i + 1 + k] : NULL;
        v[k] = s ? strtod(s, &end) : 0.0;
        if (!s || end == s || *end != '\0' || !isfinite(v[k]) || fabs(v[k]) > 1e18) {
            fprintf(stderr,
                    "irrcache points: --grid needs six numbers x0 y0 z0 x1 y1 z1 (the room's floor corner and the "
                    "opposite top corner); number %d is %s\n",
                    k + 1, s ? s : "missing");
            return 0;
        }
    }
    spec->lo = (ic_vec3){(float)v[0], (float)v[1], (float)v[2]};
    spec->hi = (ic_vec3){(float)v[3], (float)v[4], (float)v[5]};
    *i += 6;
    return 1;
}

int ic_cli_grid_map(const char *path, const ic_point_result *res, uint32_t cols, uint32_t rows, double df_lux,
                    double max)
{
    size_t n = (size_t)cols * rows;
    double *values = malloc(sizeof *values * (n ? n : 1));
    if (!values) {
        fprintf(stderr, "irrcache points: %s: out of memory for the map\n", path);
        return 0;
    }
    for (size_t k = 0; k < n; ++k)
        values[k] = df_lux > 0.0 ? 100.0 * res[k].illuminance / df_lux : res[k].illuminance;
    ic_falsecolor_options opt = {0};
    opt.max = max;
    opt.unit = df_lux > 0.0 ? "df %" : "lux";
    uint8_t *rgb = NULL;
    ic_falsecolor_layout lay;
    ic_error err = {0};
    ic_result r = ic_falsecolor_render(values, (int)cols, (int)rows, &opt, &rgb, &lay, &err);
    if (r == IC_OK)
        r = ic_image_write_png8(path, rgb, lay.width, lay.height, &err);
    if (r != IC_OK)
        fprintf(stderr, "irrcache points: --map %s: %s\n", path, err.message);
    free(rgb);
    free(values);
    return r == IC_OK;
}
