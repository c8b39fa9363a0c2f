/* points_grid.h — the false-colour map of the work-plane grid of `irrcache points --grid` (points_grid.c). */
#ifndef IC_CLI_POINTS_GRID_H
#define IC_CLI_POINTS_GRID_H

#include "irrcache/points.h"

/* Writes the false-colour PNG of a cols × rows grid's results (row 0, the smallest z, at the top: a plan
 * seen from above with +x to the right): illuminance in lux, or with df_lux > 0 the daylight factor in %,
 * on a scale from 0 to max (0: the largest value). Prints the one-line error and returns 0 on failure. */
int ic_cli_grid_map(const char *path, const ic_point_result *res, uint32_t cols, uint32_t rows, double df_lux,
                    double max);

#endif
