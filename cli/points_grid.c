/*
 * points_grid.c — `irrcache points --grid`: writing the false-colour map of its results (the map itself
 * is drawn by ic_falsecolor_render, the grid made by ic_points_grid; --grid's six numbers are parsed from
 * its row in options.h).
 */
#include "points_grid.h"
#include "cli.h"

#include "irrcache/image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int ic_cli_grid_map(const char *path, const ic_point_result *res, uint32_t cols, uint32_t rows, double df_lux,
                    double max)
{
    size_t n = (size_t)cols * rows;
    double *values = malloc(sizeof *values * (n ? n : 1));
    if (!values) {
        ic_cli_eprintf("irrcache points: %s: out of memory for the map\n", path);
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
        ic_cli_eprintf("irrcache points: --map %s: %s\n", path, err.message);
    free(rgb);
    free(values);
    return r == IC_OK;
}
