/*
 * points.c — `irrcache points SCENE --points FILE|-`: irradiance and illuminance at sensor points
 * (include/irrcache/points.h). Input lines are `x y z nx ny nz` (the order of Radiance's `rtrace -I`),
 * separated by spaces, tabs or commas, with `#` comments and blank lines; output is one line per point in
 * input order: irradiance R G B (the scene's radiometric units, W/m²), illuminance (lux, Radiance's
 * 179 lm/W convention) and its one-sigma error (lux), with --daylight-factor the daylight factor (%) and
 * its σ, as text, CSV or JSON, to stdout or atomically to -o FILE.
 *
 * Exit status: 0 success, 1 a failure while working (unreadable or malformed points file, scene,
 * output), 2 a usage error. A malformed line is reported as "FILE:LINE: problem; what to do", and then
 * no output file is written.
 */
#include "cli.h"
#include "cluster.h"
#include "json_out.h"
#include "options.h"
#include "outputs.h"
#include "points_grid.h"

#include "core/atomic_file.h"
#include "core/text.h"
#include "irrcache/image.h"
#include "irrcache/points.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

#define EXIT_WORK 1
#define EXIT_USAGE 2

/* --format's values, in the order of its declaration (options.h). */
typedef enum out_format { FORMAT_TEXT, FORMAT_CSV, FORMAT_JSON, FORMAT_RTRACE } out_format;

/* The points file's limits: lines (a sensor's six numbers and a comment fit many times over) and, as
 * --max-points, their count, so that neither /dev/zero nor a runaway generator grows memory unbounded. */
#define MAX_POINT_LINE IC_CLI_MAX_POINT_LINE

/* The options points takes from render's table: their names, values, checks and help are render's. */
static const ic_arg_id shared_ids[] = {IC_ARG_ACCURACY, IC_ARG_RAYS, IC_ARG_MAX_DEPTH, IC_ARG_SEED, IC_ARG_THREADS,
                                       IC_ARG_QUIET, IC_CLI_LOAD_OPTION_IDS};

/* The progress line on stderr (a terminal's, rank 0's, without --quiet): the phase, its share ('-' where the
 * library cannot say) and the elapsed time, redrawn at most ten times a second; cleared at the end. */
typedef struct points_progress {
    double start, last;
    const char *phase;
    int shown;
} points_progress;

static void on_progress(void *user, const char *phase, double fraction)
{
    points_progress *p = user;
    double t = ic_cli_seconds();
    if (p->phase == phase && t - p->last < 0.1 && fraction < 1.0)
        return;
    p->last = t;
    p->phase = phase;
    p->shown = 1;
    char share[16] = "-";
    if (fraction >= 0.0)
        snprintf(share, sizeof share, "%5.1f%%", 100.0 * fmin(fraction, 1.0));
    fprintf(stderr, "\r%-16s %6s  elapsed %6.1fs ", phase, share, t - p->start);
    fflush(stderr);
}

static void print_help(FILE *out)
{
    fprintf(out,
            "usage: irrcache points SCENE --points FILE|- [options]\n"
            "       irrcache points SCENE --grid X0 Y0 Z0 X1 Y1 Z1 --spacing S [--map FILE.png] [options]\n"
            "\n"
            "Irradiance and illuminance at sensor points. Each input line is 'x y z nx ny nz' (a point and\n"
            "the direction its sensor faces, as for Radiance's rtrace -I), separated by spaces, tabs or\n"
            "commas; '#' starts a comment, blank lines are skipped. Output: one line per point, in input\n"
            "order:\n"
            "  E_r E_g E_b  irradiance (the scene's radiometric units: W/m2)\n"
            "  lux          illuminance, 179 lm/W x (0.265074 E_r + 0.670115 E_g + 0.064811 E_b) (Radiance's\n"
            "               convention, so that numbers compare)\n"
            "  sigma        one-sigma Monte Carlo error of the illuminance (lux): pt, from 16 independent\n"
            "               replicates per point; ic, those of the direct light with the records' noise\n"
            "               (their own rays' and that of the records those read), without the\n"
            "               interpolation's bias, which --accuracy bounds\n"
            "Options take their value as --name VALUE or --name=VALUE (--grid: six arguments).\n"
            "\n"
            "options:\n");
    ic_cli_print_command_options(out, IC_CLI_POINTS, 21);
    fprintf(out, "options as for irrcache render (the sensor is the first scattering event; ic needs --max-depth 2\n"
                 "or more):\n");
    /* Sensors use Ward's weights (no --weight): only their accuracy default applies. */
    for (size_t k = 0; k < sizeof shared_ids / sizeof shared_ids[0]; ++k)
        if (shared_ids[k] == IC_ARG_ACCURACY)
            ic_cli_print_option_default(out, shared_ids[k], IC_DEFAULT_ACCURACY_WARD, 21);
        else
            ic_cli_print_option(out, shared_ids[k], 21);
    fprintf(out, "\nexit status: 0 success, 1 unreadable or malformed points file, scene or output, 2 usage error\n");
}

/* The README's table of points' options, and a line naming those it takes from render. */
static void print_markdown(FILE *out)
{
    ic_cli_print_command_markdown(out, IC_CLI_POINTS);
    fprintf(out, "\nAs for `render` (the same values and checks; its table's help lines in `points --help`):");
    for (size_t k = 0; k < sizeof shared_ids / sizeof shared_ids[0]; ++k) {
        char name[96];
        ic_cli_option_markdown(shared_ids[k], name, sizeof name);
        fprintf(out, "%s %s", k ? "," : "", name);
    }
    fprintf(out, ".\n");
}

/* The first 40 bytes of a token of len bytes, for a message: bytes that are not printable ASCII as \xNN, so that
 * a byte order mark, a non-breaking space or a typographic minus (U+2212) pasted from a document shows. */
static void token_text(const char *at, size_t len, char *out, size_t size)
{
    size_t o = 0;
    for (size_t k = 0; k < len && k < 40 && o + 5 < size; ++k) {
        unsigned char c = (unsigned char)at[k];
        o += (size_t)snprintf(out + o, size - o, c >= 0x20 && c < 0x7f ? "%c" : "\\x%02X", c);
    }
    out[o] = '\0';
}

/* The points of one line: 1 if it holds a point, 0 if blank or a comment, -1 if malformed (message in why).
 * Numbers are separated by spaces and tabs, or by commas (CSV, spaces allowed around them); a line that
 * separates some numbers by a comma and others by spaces alone ('0,5 0,8 1,0': decimal commas) or has an
 * empty field is refused, as is a number run into more text ('0.8.1'), where reading on would give other
 * numbers than were meant. */
static int parse_line(char *line, ic_sensor_point *pt, char *why, size_t why_size)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    double v[6];
    int count = 0, with_comma = 0, without_comma = 0;
    char *at = line;
    for (;;) {
        int commas = 0;
        while (*at == ' ' || *at == '\t' || *at == '\r' || *at == '\n' || *at == ',')
            commas += *at++ == ',';
        if (*at == '\0')
            break; /* a trailing comma ends the line, as spreadsheets write it */
        if (commas > (count > 0)) {
            snprintf(why, why_size, "an empty field %s number %d; give 'x y z nx ny nz'", count ? "after" : "before",
                     count ? count : 1);
            return -1;
        }
        if (count > 0) {
            with_comma += commas == 1;
            without_comma += commas == 0;
        }
        char *end = NULL;
        double x = strtod(at, &end);
        size_t len = strcspn(at, " \t\r\n,");
        if (end == at || end != at + len) {
            char token[168];
            token_text(at, len, token, sizeof token);
            /* A JSON, XML or Radiance scene given as the points (the two swapped) says so. */
            snprintf(why, why_size, "'%s' is not a number; give 'x y z nx ny nz' ('#' starts a comment)%s", token,
                     strchr("{<", *at) ? "; is this the scene? the scene comes first: irrcache points SCENE --points "
                                         "FILE" : "");
            return -1;
        }
        if (count == 6) {
            snprintf(why, why_size, "more than 6 numbers; give 'x y z nx ny nz' (one point per line)");
            return -1;
        }
        if (!isfinite(x)) {
            snprintf(why, why_size, "number %d is not finite; give finite coordinates", count + 1);
            return -1;
        }
        v[count++] = x;
        at = end;
    }
    if (with_comma && without_comma) {
        snprintf(why, why_size, "some numbers separated by commas, some by spaces only (a decimal comma?); write "
                 "decimals with '.' and separate all numbers alike");
        return -1;
    }
    if (count == 0)
        return 0;
    if (count != 6) {
        snprintf(why, why_size, "%d number%s, expected 6: 'x y z nx ny nz'", count, count == 1 ? "" : "s");
        return -1;
    }
    for (int k = 0; k < 3; ++k)
        if (fabs(v[k]) > IC_MAX_POINT_COORDINATE) {
            snprintf(why, why_size, "coordinate %d (%g) lies beyond 1e18; give positions in the scene's units", k + 1,
                     v[k]);
            return -1;
        }
    for (int k = 3; k < 6; ++k)
        if (fabs(v[k]) > 3e38) {
            snprintf(why, why_size, "number %d is out of range; give values below 3e38", k + 1);
            return -1;
        }
    pt->position = (ic_vec3){(float)v[0], (float)v[1], (float)v[2]};
    pt->normal = (ic_vec3){(float)v[3], (float)v[4], (float)v[5]};
    /* As stored (float): a normal like 1e-50 0 0 is zero there. */
    if (pt->normal.x == 0.0f && pt->normal.y == 0.0f && pt->normal.z == 0.0f) {
        snprintf(why, why_size, "the normal (%g %g %g) is zero or too small; give the direction the sensor faces",
                 v[3], v[4], v[5]);
        return -1;
    }
    return 1;
}

/* The next line of f into buf (MAX_POINT_LINE + 1 bytes; its newline dropped), *len its length: 1, 0 at
 * the end, -1 if it is longer than MAX_POINT_LINE (the rest is not read), -2 if it holds a NUL byte. A
 * Windows line end's CR is the line end's, not the line's: a line of MAX_POINT_LINE bytes ends in CRLF. */
static int next_line(FILE *f, char *buf, ssize_t *len)
{
    int c, n = 0, nul = 0;
    while ((c = getc(f)) != EOF && c != '\n') {
        if (n == MAX_POINT_LINE) {
            if (c == '\r' && ((c = getc(f)) == '\n' || c == EOF))
                break;
            return -1;
        }
        nul |= c == '\0';
        buf[n++] = (char)c;
    }
    buf[n] = '\0';
    *len = n;
    return nul ? -2 : c == EOF && n == 0 ? 0 : 1;
}

/* Reads every point of path ('-': stdin) into *out (malloc'd); prints the one-line error and returns 0
 * on failure. */
static int read_points(const char *path, uint32_t max_points, ic_sensor_point **out, uint32_t *count)
{
    int is_stdin = strcmp(path, "-") == 0;
    const char *name = is_stdin ? "<stdin>" : path;
    FILE *f = is_stdin ? stdin : fopen(path, "r");
    if (!f) {
        ic_cli_eprintf("irrcache points: %s: cannot open: %s; check the path\n", path, strerror(errno));
        return 0;
    }
    ic_sensor_point *pts = NULL;
    size_t n = 0, cap = 0;
    char *line = NULL;
    long line_no = 0;
    int ok = 1;
    ssize_t len;
    line = malloc(MAX_POINT_LINE + 1);
    if (!line) {
        ic_cli_eprintf("irrcache points: out of memory\n");
        ok = 0;
    }
    int got;
    while (line && (got = next_line(f, line, &len)) != 0) {
        ++line_no;
        if (got < 0) {
            ic_cli_eprintf(got == -1 ? "irrcache points: %s:%ld: a line longer than %d bytes; give one point 'x y z "
                                        "nx ny nz' a line\n"
                                      : "irrcache points: %s:%ld: a NUL byte: not a text file, or UTF-16 text (as "
                                        "spreadsheets save 'Unicode text'); save it as UTF-8 or ASCII text\n",
                    name, line_no, MAX_POINT_LINE);
            ok = 0;
            break;
        }
        /* A UTF-8 byte order mark, which Windows editors and spreadsheets put at the start of a text file. */
        int bom = line_no == 1 && len >= 3 && memcmp(line, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
        ic_sensor_point pt;
        char why[320];
        int r = parse_line(line + bom, &pt, why, sizeof why);
        if (r < 0) {
            ic_cli_eprintf("irrcache points: %s:%ld: %s\n", name, line_no, why);
            ok = 0;
            break;
        }
        if (r == 0)
            continue;
        if (n == max_points) {
            ic_cli_eprintf("irrcache points: %s:%ld: more than %u points (--max-points); raise it if the memory is "
                    "there, or split the file\n", name, line_no, max_points);
            ok = 0;
            break;
        }
        if (n == cap) {
            size_t nc = cap ? 2 * cap : 256;
            ic_sensor_point *np = realloc(pts, nc * sizeof *np);
            if (!np) {
                ic_cli_eprintf("irrcache points: %s:%ld: out of memory for the points\n", name, line_no);
                ok = 0;
                break;
            }
            pts = np;
            cap = nc;
        }
        pts[n++] = pt;
    }
    if (ok && ferror(f)) {
        int e = errno;
        if (e == EISDIR)
            ic_cli_eprintf("irrcache points: %s: is a folder; give the points file\n", name);
        else
            ic_cli_eprintf("irrcache points: %s: read error after line %ld: %s\n", name, line_no, strerror(e));
        ok = 0;
    }
    if (ok && n == 0) {
        ic_cli_eprintf("irrcache points: %s: no points (%s); give lines 'x y z nx ny nz'\n", name,
                line_no ? "only comments or blank lines" : "it is empty");
        ok = 0;
    }
    free(line);
    if (!is_stdin)
        fclose(f);
    if (!ok) {
        free(pts);
        return 0;
    }
    *out = pts;
    *count = (uint32_t)n;
    return 1;
}

/* Three floats as a JSON array of their shortest decimals (ic_float_text). */
static cJSON *json_floats(ic_vec3 v)
{
    const float f[3] = {v.x, v.y, v.z};
    double d[3];
    char buf[32];
    for (int k = 0; k < 3; ++k)
        d[k] = strtod(ic_float_text(f[k], buf), NULL);
    return cJSON_CreateDoubleArray(d, 3);
}

/* df_lux: the daylight factor's reference illuminance (0: no daylight-factor columns); pts: the points, to
 * start each row with (a generated grid), or NULL. */
static void write_rows(FILE *f, out_format format, const ic_point_result *res, uint32_t count, double df_lux,
                       const ic_sensor_point *pts)
{
    if (format == FORMAT_RTRACE) {
        /* rtrace's ASCII output (its puta): every value as %e followed by a tab, a newline after each ray */
        for (uint32_t i = 0; i < count; ++i)
            fprintf(f, "%e\t%e\t%e\t\n", (double)res[i].irradiance.x, (double)res[i].irradiance.y,
                    (double)res[i].irradiance.z);
        return;
    }
    if (format == FORMAT_CSV)
        fprintf(f, "%sirradiance_r,irradiance_g,irradiance_b,illuminance_lux,sigma_lux%s\n",
                pts ? "x,y,z,nx,ny,nz," : "", df_lux > 0.0 ? ",daylight_factor_percent,daylight_factor_sigma_percent" : "");
    const char *sep = format == FORMAT_CSV ? "," : " ";
    char b[6][32];
    for (uint32_t i = 0; i < count; ++i) {
        if (pts)
            fprintf(f, "%s%s%s%s%s%s%s%s%s%s%s%s", ic_float_text(pts[i].position.x, b[0]), sep,
                    ic_float_text(pts[i].position.y, b[1]), sep, ic_float_text(pts[i].position.z, b[2]), sep,
                    ic_float_text(pts[i].normal.x, b[3]), sep, ic_float_text(pts[i].normal.y, b[4]), sep,
                    ic_float_text(pts[i].normal.z, b[5]), sep);
        fprintf(f, "%s%s%s%s%s%s%.7g%s%.4g", ic_float_text(res[i].irradiance.x, b[0]), sep,
                ic_float_text(res[i].irradiance.y, b[1]), sep, ic_float_text(res[i].irradiance.z, b[2]), sep,
                res[i].illuminance, sep, res[i].illuminance_sigma);
        if (df_lux > 0.0)
            fprintf(f, "%s%.6g%s%.4g", sep, 100.0 * res[i].illuminance / df_lux, sep,
                    100.0 * res[i].illuminance_sigma / df_lux);
        fputc('\n', f);
    }
}

static int write_json(const char *path, const ic_points_options *opt, const ic_point_result *res, uint32_t count,
                      const ic_points_stats *st, double df_lux, const ic_sensor_point *pts)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "integrator", opt->integrator == IC_INTEGRATOR_IC ? "ic" : "pt");
    cJSON_AddNumberToObject(root, "luminous_efficacy", IC_LUMINOUS_EFFICACY);
    cJSON_AddItemToObject(root, "records", ic_cli_json_u64(st->records));
    cJSON_AddItemToObject(root, "hit_records", ic_cli_json_u64(st->hit_records));
    cJSON_AddNumberToObject(root, "seconds", st->seconds);
    if (df_lux > 0.0)
        cJSON_AddNumberToObject(root, "daylight_reference_lux", df_lux);
    cJSON *arr = cJSON_AddArrayToObject(root, "points");
    for (uint32_t i = 0; i < count; ++i) {
        cJSON *o = cJSON_CreateObject();
        if (pts)
            cJSON_AddItemToObject(o, "position", json_floats(pts[i].position));
        cJSON_AddItemToObject(o, "irradiance", json_floats(res[i].irradiance));
        cJSON_AddItemToObject(o, "irradiance_sigma", json_floats(res[i].irradiance_sigma));
        cJSON_AddNumberToObject(o, "illuminance", res[i].illuminance);
        cJSON_AddNumberToObject(o, "sigma", res[i].illuminance_sigma);
        if (df_lux > 0.0) {
            cJSON_AddNumberToObject(o, "daylight_factor", 100.0 * res[i].illuminance / df_lux);
            cJSON_AddNumberToObject(o, "daylight_factor_sigma", 100.0 * res[i].illuminance_sigma / df_lux);
        }
        cJSON_AddItemToArray(arr, o);
    }
    return ic_cli_write_json("points", path, root, 0);
}

static int points_command(int argc, char **argv, ic_comm *comm);

/* Before the work: the outputs can be written (ic_cli_check_outputs: not a folder, a device or a pipe, in a
 * folder that takes a new file, neither the other output nor an input), and a --map of cols x rows cells
 * fits the false-colour map's limits. 0 if not, the one-line message printed or in message. */
/* The files the command writes (-o, --map; NULL: not given), into outs; returns their count. */
static int list_outputs(const char *out_path, const char *map_path, ic_cli_output outs[2])
{
    int n_outs = 0;
    if (out_path)
        outs[n_outs++] = (ic_cli_output){"-o", out_path, "results.txt"};
    if (map_path)
        outs[n_outs++] = (ic_cli_output){"--map", map_path, "map.png"};
    return n_outs;
}

static int preflight(const char *scene_path, const char *points_path, const char *out_path, const char *map_path,
                     uint32_t cols, uint32_t rows, char *message, size_t size)
{
    ic_cli_output outs[2];
    int n_outs = list_outputs(out_path, map_path, outs);
    const ic_cli_input ins[2] = {{"the scene file", scene_path, NULL}, {"the --points file", points_path, NULL}};
    if (!ic_cli_check_outputs("irrcache points", outs, n_outs, ins, 2))
        return 0;
    if (!map_path)
        return 1;
    size_t n = (size_t)cols * rows;
    double *zero = calloc(n ? n : 1, sizeof *zero);
    uint8_t *rgb = NULL;
    ic_falsecolor_options fo = {0};
    ic_falsecolor_layout lay;
    ic_error err = {0};
    ic_result r = zero ? ic_falsecolor_render(zero, (int)cols, (int)rows, &fo, &rgb, &lay, &err) : IC_ERR_OOM;
    free(zero);
    free(rgb);
    if (r != IC_OK)
        snprintf(message, size, "irrcache points: --map %s: a %u x %u grid does not fit a map (%s); give a larger "
                 "--spacing, or leave out --map", map_path, cols, rows, r == IC_ERR_OOM ? "out of memory" : err.message);
    return r == IC_OK;
}

int ic_cli_points(int argc, char **argv)
{
    int failed = 0;
    ic_comm *comm = ic_cli_cluster_start(&argc, &argv, &failed);
    if (failed)
        return EXIT_WORK;
    int rc = points_command(argc, argv, comm);
    ic_cli_cluster_end(comm);
    return rc;
}

/* Before the computation: what failed on this rank, agreed on by every rank (ic_cli_cluster_agree). */
static int agree(ic_comm *comm, int status, const char *message)
{
    return ic_cli_cluster_agree(comm, status, message, NULL);
}

/* Under mpirun (cluster.h) every rank computes a share of the records and the points; ranks other than 0
 * parse the same command line silently (rank 0 reports its errors), rank 0 alone reads a points file (so
 * standard input works) and broadcasts it, and alone writes the results. */
static int points_command(int argc, char **argv, ic_comm *comm)
{
    int rank = ic_cli_cluster_rank(comm), ranks = ic_cli_cluster_size(comm);
    int muted = ic_cli_cluster_mute(rank != 0);
    const char *scene_path = NULL;
    ic_points_args own; /* points' own options, by its table (options.h) */
    ic_cli_command_defaults(IC_CLI_POINTS, &own);
    ic_cli_args args; /* the options shared with render (load limits, depth, seed, threads, cache), by its table */
    memset(&args, 0, sizeof args);
    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        int shared = 0, rc;
        if (arg[0] != '-' || arg[1] == '\0') {
            if (scene_path) {
                ic_cli_eprintf("irrcache points: %s: unexpected extra argument; give one scene, and a points file "
                        "after --points (--points %s)\n", arg, arg);
                return EXIT_USAGE;
            }
            scene_path = arg;
        } else if ((shared = ic_cli_parse_shared_option(argc, argv, &i, &args, "points", shared_ids,
                                                        sizeof shared_ids / sizeof shared_ids[0])) != 0) {
            if (shared < 0)
                return EXIT_USAGE;
        } else if ((rc = ic_cli_parse_command_option(IC_CLI_POINTS, argc, argv, &i, &own)) < 0) {
            if (rank != 0)
                return 0;
            if (rc == -1 - IC_POINTS_ARG_HELP_MARKDOWN)
                print_markdown(stdout);
            else
                print_help(stdout);
            return ic_cli_flush_stdout("irrcache points");
        } else if (rc) {
            return EXIT_USAGE;
        }
    }
    const char *points_path = own.points, *out_path = own.output, *map_path = own.map;
    if (out_path && strcmp(out_path, "-") == 0)
        out_path = NULL; /* standard output, as '--points -' reads standard input */
    out_format format = (out_format)own.format;
    int has_grid = own.given[IC_POINTS_ARG_GRID] != NULL, has_spacing = own.given[IC_POINTS_ARG_SPACING] != NULL,
        has_height = own.given[IC_POINTS_ARG_HEIGHT] != NULL, has_map_max = own.given[IC_POINTS_ARG_MAP_MAX] != NULL;
    size_t map_len = map_path ? strlen(map_path) : 0;
    if (map_path && (map_len < 4 || strcasecmp(map_path + map_len - 4, ".png") != 0)) {
        ic_cli_eprintf("irrcache points: --map %s: the map is a PNG; give a path ending in .png\n", map_path);
        return EXIT_USAGE;
    }
    ic_points_grid_spec grid = {0};
    grid.lo = (ic_vec3){(float)own.grid[0], (float)own.grid[1], (float)own.grid[2]};
    grid.hi = (ic_vec3){(float)own.grid[3], (float)own.grid[4], (float)own.grid[5]};
    grid.spacing = own.spacing;
    grid.height = own.height;
    ic_points_options opt;
    memset(&opt, 0, sizeof opt);
    opt.integrator = (ic_integrator)own.integrator;
    opt.samples = own.samples;
    opt.light_samples = own.light_samples;
    if (args.given[IC_ARG_MAX_DEPTH])
        opt.max_depth = args.render.max_depth;
    if (args.given[IC_ARG_THREADS])
        opt.threads = args.render.threads;
    if (args.given[IC_ARG_SEED]) {
        opt.seed = args.render.seed;
        opt.has_seed = 1;
    }
    if (args.given[IC_ARG_RAYS]) {
        opt.ic.gather.theta_strata = args.render.ic.gather.theta_strata;
        opt.ic.gather.phi_strata = args.render.ic.gather.phi_strata;
    }
    if (args.given[IC_ARG_ACCURACY])
        opt.ic.cache.accuracy = args.render.ic.cache.accuracy;
    /* An option of the other estimator did nothing, without a word (--samples with the default cache: the
     * user thought 4096 paths ran); refused as render refuses cache options without the cache. */
    const int is_ic = own.integrator == IC_INTEGRATOR_IC;
    const char *other_estimator =
        is_ic && own.given[IC_POINTS_ARG_SAMPLES] ? "--samples is the path tracer's; add --integrator pt, or give the "
                                                    "cache --light-samples (its direct light) or --rays (its records)"
        : !is_ic && own.given[IC_POINTS_ARG_LIGHT_SAMPLES] ? "--light-samples is the cache's; add --integrator ic, or "
                                                             "give the path tracer --samples"
        : !is_ic && args.given[IC_ARG_ACCURACY] ? "--accuracy is the cache's; add --integrator ic"
        : !is_ic && args.given[IC_ARG_RAYS]     ? "--rays is the cache's; add --integrator ic, or give the path tracer "
                                                  "--samples"
                                                : NULL;
    const char *misuse = !scene_path                          ? "no scene given"
                         : other_estimator                    ? other_estimator
                         : has_grid && points_path            ? "--grid and --points both given; give one"
                         : !has_grid && !points_path          ? "no --points FILE given ('-' reads standard input) and no --grid"
                         : has_grid && !has_spacing           ? "--grid needs --spacing S (the distance between sensors)"
                         : !has_grid && (has_spacing || has_height || map_path)
                             ? "--spacing, --height and --map apply to a --grid"
                         : has_map_max && !map_path           ? "--map-max applies to a --map"
                         : format == FORMAT_RTRACE && (has_grid || own.daylight_factor)
                             ? "--format rtrace prints the irradiance alone, as rtrace -I does, without a --grid's "
                               "points or --daylight-factor's columns; give text, csv or json"
                         : has_grid && own.given[IC_POINTS_ARG_MAX_POINTS]
                             ? "--max-points applies to a --points file; a --grid's size is set by its --spacing"
                                                              : NULL;
    if (misuse) {
        ic_cli_eprintf("irrcache points: %s; usage: irrcache points SCENE --points FILE|- [options] or irrcache "
                        "points SCENE --grid x0 y0 z0 x1 y1 z1 --spacing S [options]\n",
                misuse);
        return EXIT_USAGE;
    }

    ic_sensor_point *pts = NULL;
    uint32_t count = 0, cols = 0, rows = 0;
    ic_cli_cluster_unmute(muted);
    char message[1400] = "";
    int rc = 0;
    if (has_grid) {
        /* Every rank makes the same grid; a failure on one (out of memory) must stop them all. */
        ic_error gerr = {0};
        ic_result gr = ic_points_grid(&grid, &pts, &cols, &rows, &gerr);
        if (gr != IC_OK) {
            /* The library's message starts "grid: ": said once, as the option. */
            const char *what = strncmp(gerr.message, "grid: ", 6) == 0 ? gerr.message + 6 : gerr.message;
            snprintf(message, sizeof message, "irrcache points: %s--grid: %s", ranks > 1 && gr == IC_ERR_OOM ?
                     "on one rank: " : "", what);
            rc = gr == IC_ERR_OOM ? EXIT_WORK : EXIT_USAGE;
        }
        count = cols * rows;
    } else if (rank == 0 && !read_points(points_path, (uint32_t)own.max_points, &pts, &count)) {
        rc = EXIT_WORK;
    }
    /* What would fail only at the end, after all the work, is checked now (rank 0 writes). */
    if (rc == 0 && rank == 0 && !preflight(scene_path, points_path, out_path, map_path, cols, rows, message,
                                           sizeof message))
        rc = EXIT_WORK;
    if ((rc = agree(comm, rc, message)) != 0) {
        free(pts);
        return rc;
    }
    if (ranks > 1 && !has_grid) {
        uint64_t n = count;
        ic_cli_cluster_broadcast(comm, &n, sizeof n);
        count = (uint32_t)n;
        if (rank != 0 && !(pts = malloc(sizeof *pts * (count ? count : 1)))) {
            ic_cli_eprintf("irrcache points: rank %d of %d: out of memory for %u points\n", rank, ranks, count);
            ic_cli_cluster_abort(comm, EXIT_WORK);
        }
        ic_cli_cluster_broadcast(comm, pts, sizeof *pts * count);
    }
    opt.comm = comm;
    const ic_sensor_point *prefix = has_grid ? pts : NULL;
    ic_error err = {0};
    ic_scene *scene = NULL;
    ic_point_result *res = malloc(sizeof *res * count);
    ic_points_stats st;
    double df_lux = 0.0;
    int status = EXIT_WORK;
    if (!res)
        snprintf(message, sizeof message, "irrcache points: out of memory for %u results", count);
    else if (ic_scene_load(scene_path, &args.load, &scene, &err) != IC_OK && ranks > 1)
        snprintf(message, sizeof message, "irrcache points: rank %d of %d: %s", rank, ranks, err.message);
    else if (!scene)
        snprintf(message, sizeof message, "irrcache points: %s", err.message);
    else if (own.daylight_factor && ic_points_daylight_reference(scene, &df_lux, &err) != IC_OK)
        snprintf(message, sizeof message, "irrcache points: --daylight-factor: %s", err.message);
    /* The files the scene read (its meshes, textures, ...) are known now: no output may be one of them. */
    ic_cli_output outs[2];
    const int n_outs = list_outputs(out_path, map_path, outs);
    const int overwrites = !message[0] && rank == 0 &&
                           !ic_cli_check_scene_files("irrcache points", outs, n_outs, scene);
    if ((rc = agree(comm, message[0] || overwrites ? EXIT_WORK : 0, message)) != 0) {
        ic_scene_free(scene);
        free(res);
        free(pts);
        return rc;
    }
    if (rank == 0)
        ic_cli_scene_warnings("irrcache points", scene, scene_path, "every sensor will read 0");
    points_progress prog = {ic_cli_seconds(), 0.0, NULL, 0};
    if (rank == 0 && !args.quiet && isatty(fileno(stderr))) {
        opt.progress = on_progress;
        opt.progress_user = &prog;
    }
    ic_result computed = ic_points_compute(scene, pts, count, &opt, res, &st, &err);
    if (prog.shown)
        fprintf(stderr, "\r%48s\r", "");
    if (computed != IC_OK) {
        if (ranks > 1) {
            /* As in render.c: rank 0 says a failure every rank meets; the others' abort ends the job. */
            if (rank != 0)
                nanosleep(&(struct timespec){1, 0}, NULL);
            ic_cli_eprintf("irrcache points: rank %d of %d: %s: %s; stopping all ranks\n", rank, ranks,
                    has_grid ? "--grid" : points_path, err.message);
            ic_cli_cluster_abort(comm, EXIT_WORK);
        }
        if (err.code == IC_ERR_INVALID_ARG) {
            /* an option the scene's settings make impossible (the points themselves were checked here) */
            ic_cli_eprintf("irrcache points: %s\n", err.message);
            status = EXIT_USAGE;
        } else {
            ic_cli_eprintf("irrcache points: %s: %s\n", has_grid ? "--grid" : points_path, err.message);
        }
    } else if (rank != 0) {
        status = 0; /* rank 0 writes the results */
    } else if (map_path && !ic_cli_grid_map(map_path, res, cols, rows, df_lux, own.map_max)) {
        /* the map first: when it cannot be written, no results file is left either */
    } else if (format == FORMAT_JSON) {
        status = write_json(out_path, &opt, res, count, &st, df_lux, prefix) ? 0 : EXIT_WORK;
    } else if (!out_path) {
        write_rows(stdout, format, res, count, df_lux, prefix);
        status = ic_cli_flush_stdout("irrcache points") ? EXIT_WORK : 0;
    } else {
        ic_atomic_file f;
        if (ic_atomic_file_open(&f, out_path, &err) != IC_OK) {
            ic_cli_eprintf("irrcache points: %s\n", err.message);
        } else {
            write_rows(f.fp, format, res, count, df_lux, prefix);
            if (ic_atomic_file_commit(&f, &err) != IC_OK)
                ic_cli_eprintf("irrcache points: %s\n", err.message);
            else
                status = 0;
        }
    }
    ic_scene_free(scene);
    free(res);
    free(pts);
    return status;
}
