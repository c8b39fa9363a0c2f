/*
 * test_cli_points.c — `irrcache points`: results in input order in the three formats, stdin and -o,
 * identical output for 1 and 2 threads, and malformed points files: a one-line error naming the file and
 * line, exit 1, and no output file (nor a temporary one) left behind; --daylight-factor's columns; --grid's
 * rows and its --map (size, and each cell's colour against the scale for its lux); misused grid options;
 * the scene's warnings on stderr.
 */
#include "test_util.h"

#include "irrcache/image.h"

#include "test_files.h"
#include "test_render_util.h"

#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#define CLI IC_CLI_PATH
#define SCENE IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"
#define DIR IC_TEST_TMP "/cli_points"
#define ERR DIR "/stderr.txt"

static char err_text[8192];

/* Runs `irrcache points ARGS` (stderr captured, stdout to out_path or discarded); returns the exit status,
 * or -1 if it crashed. */
static int run(const char *args, const char *out_path)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s points %s >%s", CLI, args, out_path ? out_path : "/dev/null");
    return test_run_capture(cmd, ERR, err_text, sizeof err_text);
}

static char *slurp(const char *path)
{
    static char buf[65536];
    FILE *f = fopen(path, "r");
    size_t n = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
    buf[n] = 0;
    if (f)
        fclose(f);
    return buf;
}

static void test_outputs(void)
{
    test_write_file(DIR "/pts.txt", "# two sensors on a work plane, one on the left wall\n"
                                    "-0.7 0.8 0.6 0 1 0\n"
                                    "\n"
                                    "0.7 0.8 0.7   0 1 0   # right\n"
                                    "-0.98 1 0 1 0 0\n");
    CHECK(run("--help", DIR "/help.txt") == 0, "--help exits 0");
    /* Sensors take Ward's weights only: their accuracy's default alone, not render's per weight. */
    const char *acc = strstr(slurp(DIR "/help.txt"), "--accuracy A");
    const char *acc_end = acc ? strstr(acc, "\n  -") : NULL;
    CHECK(acc && acc_end && strstr(acc, "[default: 0.15]") && strstr(acc, "[default: 0.15]") < acc_end &&
              !strstr(acc, "(tl)"),
          "--help: the accuracy's default is 0.15, without tl's");
    CHECK(run(SCENE " --points " DIR "/pts.txt --threads 1", DIR "/a.txt") == 0 && err_text[0] == '\0',
          "text to stdout, nothing on stderr: %s", err_text);
    /* What the loader dropped, and a scene without light, are said on stderr as render says them. */
    CHECK(run(IC_SOURCE_DIR "/tests/scenes/degenerate.json --points " DIR "/pts.txt", NULL) == 0 &&
              strstr(err_text, "irrcache points: warning: ") && strstr(err_text, "1 triangle of zero area") &&
              strstr(err_text, "has no light") && test_line_count(err_text) == 2,
          "the scene's warnings: %s", err_text);
    char a[4096];
    snprintf(a, sizeof a, "%s", slurp(DIR "/a.txt"));
    CHECK(test_line_count(a) == 3, "one line per point: %d", test_line_count(a));
    double v[5] = {0};
    CHECK(sscanf(a, "%lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4]) == 5, "five numbers per line: %s", a);
    double lux = 179.0 * (0.265074126 * v[0] + 0.670114631 * v[1] + 0.064811243 * v[2]);
    CHECK_NEAR(v[3], lux, 1e-4 * lux, "illuminance column is 179 lm/W times the luminance");
    CHECK(v[3] > 50.0 && v[4] > 0.0 && v[4] < 0.1 * v[3], "plausible lux %g and sigma %g", v[3], v[4]);
    /* Same points through stdin, 2 threads, written with -o: the same bytes. */
    CHECK(run(SCENE " --points - --threads 2 -o " DIR "/b.txt < " DIR "/pts.txt", NULL) == 0, "stdin and -o: %s",
          err_text);
    CHECK(strcmp(a, slurp(DIR "/b.txt")) == 0, "1 and 2 threads, file and stdin: identical output");
    /* '-o -' is standard output, as '--points -' is standard input (it once wrote a file named '-'). */
    {
        char cmd[4096];
        unlink(DIR "/-");
        snprintf(cmd, sizeof cmd, "cd " DIR " && %s points " SCENE " --points pts.txt --threads 1 -o - >dash.txt", CLI);
        CHECK(test_run_capture(cmd, ERR, err_text, sizeof err_text) == 0 && strcmp(a, slurp(DIR "/dash.txt")) == 0 &&
                  !test_file_exists(DIR "/-"),
              "-o -: the results on standard output, no file '-': %s", err_text);
    }
    CHECK(run(SCENE " --points " DIR "/pts.txt --format csv --integrator pt --samples 256 -o " DIR "/c.csv", NULL) == 0,
          "csv: %s", err_text);
    const char *csv = slurp(DIR "/c.csv");
    CHECK(strncmp(csv, "irradiance_r,irradiance_g,irradiance_b,illuminance_lux,sigma_lux\n", 65) == 0 &&
              test_line_count(csv) == 4,
          "csv: a header and three rows: %s", csv);
    CHECK(run(SCENE " --points " DIR "/pts.txt --format json -o " DIR "/d.json", NULL) == 0, "json: %s", err_text);
    const char *json = slurp(DIR "/d.json");
    CHECK(strstr(json, "\"points\":[") && strstr(json, "\"illuminance\":") && strstr(json, "\"sigma\":"),
          "json has the points: %s", json);
    /* rtrace: what Radiance's rtrace -I -h- prints, "%e\t%e\t%e\t\n" a point, the text format's irradiance */
    CHECK(run(SCENE " --points " DIR "/pts.txt --threads 1 --format rtrace -o " DIR "/r.txt", NULL) == 0, "rtrace: %s",
          err_text);
    const char *rt = slurp(DIR "/r.txt"), *tx = a;
    int rows = 0;
    for (; *rt && rows < 3; ++rows) {
        double e[3], t[3];
        char again[128];
        CHECK(sscanf(rt, "%lf%lf%lf", &e[0], &e[1], &e[2]) == 3, "rtrace row %d: three numbers: %.80s", rows, rt);
        snprintf(again, sizeof again, "%e\t%e\t%e\t\n", e[0], e[1], e[2]);
        CHECK(strncmp(rt, again, strlen(again)) == 0, "rtrace row %d is each number as %%e and a tab, then a newline: "
              "%.80s", rows, rt);
        CHECK(sscanf(tx, "%lf %lf %lf", &t[0], &t[1], &t[2]) == 3, "text row %d", rows);
        for (int k = 0; k < 3; ++k)
            CHECK(fabs(e[k] - t[k]) <= 1e-6 * fabs(t[k]), "rtrace row %d channel %d: %g, the text format %g", rows, k,
                  e[k], t[k]);
        rt += strlen(again);
        tx = strchr(tx, '\n') ? strchr(tx, '\n') + 1 : "";
    }
    CHECK(rows == 3 && *rt == '\0', "rtrace: one row per point (%d), nothing else: %.80s", rows, rt);
    CHECK(run(SCENE " --grid 0 0 0 1 1 1 --spacing 0.5 --format rtrace", NULL) == 2 && strstr(err_text, "rtrace") &&
              test_line_count(err_text) == 1,
          "rtrace with a grid's points: a usage error: %s", err_text);
}

/* --daylight-factor: two more columns, 100 × lux / (179 × 7π/9 × L_z); refused (exit 1, no output) without
 * a CIE overcast sky. */
static void test_daylight_factor(void)
{
    const char *room = IC_SOURCE_DIR "/scenes/interiors/sky-room-overcast.json";
    test_write_file(DIR "/room.txt", "2.5 0.8 1.0 0 1 0\n1.5 0.8 2.5 0 1 0\n");
    char args[1024];
    snprintf(args, sizeof args, "%s --points %s/room.txt --daylight-factor --format csv", room, DIR);
    CHECK(run(args, DIR "/df.csv") == 0, "daylight factor: %s", err_text);
    const char *csv = slurp(DIR "/df.csv");
    CHECK(strstr(csv, ",daylight_factor_percent,daylight_factor_sigma_percent\n") && test_line_count(csv) == 3,
          "csv header names the daylight factor: %s", csv);
    const char *row = strchr(csv, '\n');
    double v[7] = {0};
    CHECK(row && sscanf(row + 1, "%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6]) == 7,
          "seven columns: %s", csv);
    double ref = 179.0 * 7.0 * 3.14159265358979323846 / 9.0 * (10000.0 / 179.0);
    CHECK_NEAR(v[5], 100.0 * v[3] / ref, 1e-4 * v[5] + 1e-6, "DF = 100 lux / (7 pi/9 L_z)");
    CHECK_NEAR(v[6], 100.0 * v[4] / ref, 1e-3 * v[6] + 1e-6, "its sigma likewise");
    unlink(DIR "/df-out.txt");
    CHECK(run(SCENE " --points " DIR "/pts.txt --daylight-factor -o " DIR "/df-out.txt", NULL) == 1 &&
              strstr(err_text, "cie-overcast") && !test_file_exists(DIR "/df-out.txt"),
          "no overcast sky: exit 1, no output: %s", err_text);
}

/* --grid with --map: one row per grid point, starting with the point; the map's size follows the grid and a
 * cell has the colour of its illuminance on the scale. */
static void test_grid_map(void)
{
    char args[1024];
    snprintf(args, sizeof args, "%s --grid -1 0 -1 1 1.9 1 --spacing 0.5 --height 0.8 --map %s/map.png --map-max 100",
             SCENE, DIR);
    unlink(DIR "/map.png");
    CHECK(run(args, DIR "/grid.txt") == 0, "grid and map: %s", err_text);
    char grid[65536];
    snprintf(grid, sizeof grid, "%s", slurp(DIR "/grid.txt"));
    CHECK(test_line_count(grid) == 16, "a 2 x 2 m floor at 0.5 m: 16 rows (%d)", test_line_count(grid));
    double v[11] = {0};
    CHECK(sscanf(grid, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6],
                 &v[7], &v[8], &v[9], &v[10]) == 11 &&
              fabs(v[0] + 0.75) < 1e-6 && fabs(v[1] - 0.8) < 1e-6 && fabs(v[2] + 0.75) < 1e-6 && v[4] == 1.0,
          "each row starts with its point: %.60s", grid);
    ic_image img = {0};
    ic_error err = {0};
    CHECK(ic_image_read(DIR "/map.png", &img, &err) == IC_OK, "the map decodes: %s", err.message);
    ic_falsecolor_layout lay;
    uint8_t *rgb = NULL;
    double lux[16];
    const char *row = grid;
    for (int k = 0; k < 16 && row; ++k) {
        double c[11];
        lux[k] = sscanf(row, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &c[0], &c[1], &c[2], &c[3], &c[4], &c[5],
                        &c[6], &c[7], &c[8], &c[9], &c[10]) == 11 ? c[9] : -1.0;
        row = strchr(row, '\n');
        row = row ? row + 1 : NULL;
    }
    ic_falsecolor_options fo = {0};
    fo.max = 100.0;
    CHECK(ic_falsecolor_render(lux, 4, 4, &fo, &rgb, &lay, &err) == IC_OK, "layout: %s", err.message);
    free(rgb);
    CHECK(img.width == lay.width && img.height == lay.height, "map size %d x %d, expected %d x %d", img.width,
          img.height, lay.width, lay.height);
    if (img.rgb && img.width == lay.width && img.height == lay.height) {
        int wrong = 0;
        for (int k = 0; k < 16; ++k) {
            uint8_t want[3];
            ic_falsecolor_scale(lux[k] / 100.0, want);
            int x = lay.map_x + (k % 4) * lay.cell_px + lay.cell_px / 2, y = lay.map_y + (k / 4) * lay.cell_px + lay.cell_px / 2;
            const float *p = img.rgb + 3 * ((size_t)y * (size_t)img.width + (size_t)x);
            for (int c = 0; c < 3; ++c)
                wrong += fabsf(p[c] - ic_srgb8_to_linear(want[c])) > 1e-6f;
        }
        CHECK(wrong == 0, "each cell has its lux's colour on the scale (%d channels differ)", wrong);
    }
    ic_image_free(&img);
    CHECK(run(SCENE " --grid 0 0 0 1 1 1", NULL) == 2 && strstr(err_text, "--spacing"), "--grid needs --spacing: %s",
          err_text);
    CHECK(run(SCENE " --grid 0 0 0 1 1", NULL) == 2 && strstr(err_text, "six numbers"), "five numbers: %s", err_text);
    CHECK(run(SCENE " --grid 0 0 0 1 1 2e18 --spacing 0.5", NULL) == 2 && strstr(err_text, "number 6 is 2e18") &&
              test_line_count(err_text) == 1,
          "a corner beyond 1e18: %s", err_text);
    CHECK(run(SCENE " --grid=0 --spacing 0.5", NULL) == 2 && strstr(err_text, "separate arguments"),
          "--grid=: %s", err_text);
    CHECK(run(SCENE " --grid 0 0 0 1 1 1 --spacing=0", NULL) == 2 && strstr(err_text, "--spacing 0: expected a number "
                                                                              "in (0, 1e18]"),
          "--spacing=0 (the lower end excluded): %s", err_text);
    CHECK(run(SCENE " --points " DIR "/pts.txt --map " DIR "/x.png", NULL) == 2 && strstr(err_text, "--grid"),
          "--map without a grid: %s", err_text);
    /* --max-points bounds a --points file; with a grid it was ignored without a word (16 points made). */
    CHECK(run(SCENE " --grid 0 0 0 1 1 1 --spacing 0.25 --max-points 2", NULL) == 2 &&
              strstr(err_text, "--max-points applies to a --points file") && test_line_count(err_text) == 1,
          "--max-points with a grid: %s", err_text);
    CHECK(run(SCENE " --grid 0 0 0 1 1 1 --spacing 0.5 --map " DIR "/x.jpg", NULL) == 2 && strstr(err_text, ".png"),
          "--map needs .png: %s", err_text);
    CHECK(run(SCENE " --grid 0 0 0 1 1 1 --spacing 2", NULL) == 2 && strstr(err_text, "no whole"),
          "a grid with no cell: %s", err_text);
    /* A side of whole cells as written keeps them all (0.7 m at 0.1 m: 7, though 0.7 is a float short of
     * it), and a plane at the box's top is in the box. */
    CHECK(run(SCENE " --grid 0 0 -0.7 0.7 1.9 0 --spacing 0.1 --height 1.9 --integrator pt --samples 16",
              DIR "/whole.txt") == 0 && test_line_count(slurp(DIR "/whole.txt")) == 49,
          "0.7 x 0.7 m at 0.1 m, at the box's top: 49 rows (%d): %s", test_line_count(slurp(DIR "/whole.txt")),
          err_text);
    CHECK(run(SCENE " --grid 0 0 0 1 0.5 1 --spacing 0.5", NULL) == 2 &&
              strstr(err_text, "irrcache points: --grid: the plane at y0 + height = 0.8 lies above the box's top 0.5; "
                               "give a height of at most 0.5"),
          "a plane above the box, said once as --grid, with what to do: %s", err_text);
}

/* An open ground (Kd 0.5) under a uniform sky, in DIR: cheap to compute. */
#define PLANE DIR "/plane.json"
static void write_plane(void)
{
    test_write_file(DIR "/plane.mtl", "newmtl ground\nKd 0.5 0.5 0.5\n");
    test_write_file(DIR "/plane.obj", "mtllib plane.mtl\nusemtl ground\n"
                                      "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\nv -1000 0 1000\nf 1 4 3 2\n");
    test_write_file(PLANE, "{\"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 0.001], \"up\": [0, 0, -1],\n"
                           "            \"width\": 16, \"height\": 16},\n"
                           " \"meshes\": [{\"path\": \"plane.obj\"}], \"environment\": {\"radiance\": [1, 1, 1]}}\n");
}

/* What a points file from a spreadsheet, a Windows editor or another tool may hold is read as the plain
 * file: a UTF-8 byte order mark, CRLF line ends, tabs, exponents, CSV with spaces and a trailing comma, a
 * signed zero, a last line without its newline. */
static void test_accepted_inputs(void)
{
    write_plane();
    test_write_file(DIR "/plain.txt", "0 1 0 1 0 0\n0.5 0.25 2 0 1 0\n-3 0.8 1 0 0 -1\n1 1 1 3 4 0\n");
    test_write_file(DIR "/quirky.txt", "\xEF\xBB\xBF# from a spreadsheet\r\n"
                                       "0\t1\t0\t1\t0\t0\r\n"
                                       "5e-1, 2.5E-1, 2, 0, 1, 0,\r\n"
                                       "\r\n"
                                       "-3,0.8,1,+0,-0,-1 # a comment\r\n"
                                       "1 1 1 3 4 0");
    char plain[4096];
    CHECK(run(PLANE " --points " DIR "/plain.txt --integrator pt --samples 16", DIR "/plain.out") == 0,
          "plain file: %s", err_text);
    snprintf(plain, sizeof plain, "%s", slurp(DIR "/plain.out"));
    CHECK(run(PLANE " --points " DIR "/quirky.txt --integrator pt --samples 16", DIR "/quirky.out") == 0,
          "BOM, CRLF, tabs, exponents, commas, no final newline: %s", err_text);
    CHECK(test_line_count(plain) == 4 && strcmp(plain, slurp(DIR "/quirky.out")) == 0,
          "the same points, the same results:\n%s---\n%s", plain, slurp(DIR "/quirky.out"));
}

/* The float fields read back as the same floats (shortest decimals, text and JSON agree): a grid at
 * 0.8 m reads 0.8, not 0.800000012. */
static void test_round_trip(void)
{
    const char *grid = SCENE " --grid -1 0 -1 1 1.9 1 --spacing 0.3 --rays 64 --light-samples 16";
    char args[1024], text[65536];
    snprintf(args, sizeof args, "%s", grid);
    CHECK(run(args, DIR "/rt.txt") == 0, "grid, text: %s", err_text);
    snprintf(text, sizeof text, "%s", slurp(DIR "/rt.txt"));
    snprintf(args, sizeof args, "%s --format json", grid);
    CHECK(run(args, DIR "/rt.json") == 0, "grid, json: %s", err_text);
    const char *json = slurp(DIR "/rt.json");
    CHECK(strncmp(text, "-0.75 0.8 -0.75 0 1 0 ", 22) == 0, "text: the first point as given: %.40s", text);
    CHECK(strstr(json, "\"position\":[-0.75,0.8,-0.75]") != NULL, "json: the first point as given: %.200s", json);
    int rows = 0, same = 0;
    const char *row = text, *at = json;
    while (row && *row && (at = strstr(at, "\"irradiance\":[")) != NULL) {
        char *end = (char *)row;
        for (int k = 0; k < 6; ++k)
            strtod(end, &end);
        int equal = 1;
        at += strlen("\"irradiance\":[");
        for (int c = 0; c < 3; ++c) {
            float t = strtof(end, &end);
            char *next;
            float j = (float)strtod(at, &next);
            at = next + 1;
            equal &= t == j;
        }
        same += equal;
        ++rows;
        row = strchr(row, '\n');
        row = row ? row + 1 : NULL;
    }
    CHECK(rows == 36 && same == rows, "text and json irradiance are the same floats at %d of %d rows", same, rows);
}

/* Outputs checked before any work: not a folder, a pipe, the other output, the scene or the points file;
 * nothing is written then, and the inputs are left as they were. */
static void test_outputs_refused(void)
{
    write_plane();
    const char *pts = "0 1 0 1 0 0\n";
    test_write_file(DIR "/in.txt", pts);
    mkdir(DIR "/folder.txt", 0755);
    CHECK(run(PLANE " --points " DIR "/in.txt -o " DIR "/folder.txt", NULL) == 1 &&
              strstr(err_text, "-o " DIR "/folder.txt: is a folder; give a file name") &&
              test_line_count(err_text) == 1,
          "-o onto a folder: refused before the work: %s", err_text);
    CHECK(run(PLANE " --points " DIR "/in.txt -o " DIR "/folder.txt/", NULL) == 1 &&
              strstr(err_text, "is a folder; give a file name (for example " DIR "/folder.txt/results.txt)"),
          "-o onto a folder/: %s", err_text);
    unlink(DIR "/fifo.txt");
    mkfifo(DIR "/fifo.txt", 0644);
    CHECK(run(PLANE " --points " DIR "/in.txt -o " DIR "/fifo.txt", NULL) == 1 &&
              strstr(err_text, "not a regular file"),
          "-o onto a pipe: %s", err_text);
    unlink(DIR "/fifo.txt");
    unlink(DIR "/same.png");
    CHECK(run(PLANE " --grid 0 0 0 1 1 1 --spacing 0.5 --map " DIR "/same.png -o " DIR "/./same.png", NULL) == 1 &&
              strstr(err_text, "the same file as") && !test_file_exists(DIR "/same.png"),
          "-o and --map one file: refused, nothing written: %s", err_text);
    char scene[4096];
    snprintf(scene, sizeof scene, "%s", slurp(PLANE));
    CHECK(run(PLANE " --points " DIR "/in.txt -o " PLANE, NULL) == 1 && strstr(err_text, "is the scene file") &&
              strcmp(slurp(PLANE), scene) == 0,
          "-o onto the scene: refused, the scene kept: %s", err_text);
    CHECK(run(PLANE " --points " DIR "/in.txt -o " DIR "/../cli_points/in.txt", NULL) == 1 &&
              strstr(err_text, "is the --points file") && strcmp(slurp(DIR "/in.txt"), pts) == 0,
          "-o onto the points file: refused, the points kept: %s", err_text);
    /* The points read from standard input sent from that file ('--points - < in.txt'): the same file. */
    CHECK(run(PLANE " --points - -o " DIR "/in.txt <" DIR "/in.txt", NULL) == 1 &&
              strstr(err_text, "is the --points file - (standard input") && strcmp(slurp(DIR "/in.txt"), pts) == 0,
          "-o onto the file standard input reads: refused, the points kept: %s", err_text);
    /* Nor a file the scene reads: its mesh, its MTL file, a texture (found once the scene is loaded, before
     * the work); each is left byte for byte, and a result of another name is written. */
    char mesh[4096], mtl[4096];
    snprintf(mesh, sizeof mesh, "%s", slurp(DIR "/plane.obj"));
    snprintf(mtl, sizeof mtl, "%s", slurp(DIR "/plane.mtl"));
    CHECK(run(PLANE " --points " DIR "/in.txt -o " DIR "/plane.obj", NULL) == 1 &&
              strstr(err_text, "-o " DIR "/plane.obj: is a file the scene reads") && test_line_count(err_text) == 1 &&
              strcmp(slurp(DIR "/plane.obj"), mesh) == 0,
          "-o onto the scene's mesh: refused, the mesh kept: %s", err_text);
    CHECK(run(PLANE " --points " DIR "/in.txt -o " DIR "/./plane.mtl", NULL) == 1 &&
              strstr(err_text, "is a file the scene reads") && strcmp(slurp(DIR "/plane.mtl"), mtl) == 0,
          "-o onto the mesh's MTL file: refused, kept: %s", err_text);
    /* A texture: a map made here (a PNG), then given as the ground's colour. */
    remove(DIR "/texture.png");
    CHECK(run(PLANE " --grid 0 0 0 1 1 1 --spacing 0.5 --map " DIR "/texture.png", NULL) == 0, "a PNG: %s", err_text);
    test_write_file(DIR "/textured.json", "{\"meshes\": [{\"path\": \"plane.obj\"}], \"environment\": {\"radiance\": "
                                          "[1, 1, 1]},\n \"materials\": {\"ground\": {\"kd_texture\": \"texture.png\"}}}\n");
    static char png[1 << 16], after[1 << 16];
    size_t n_png = test_read_text(DIR "/texture.png", png, sizeof png);
    CHECK(run(DIR "/textured.json --grid 0 0 0 1 1 1 --spacing 0.5 --map " DIR "/texture.png", NULL) == 1 &&
              strstr(err_text, "--map " DIR "/texture.png: is a file the scene reads"),
          "--map onto the scene's texture: refused: %s", err_text);
    CHECK(run(DIR "/textured.json --points " DIR "/in.txt -o " DIR "/texture.png", NULL) == 1 &&
              strstr(err_text, "-o " DIR "/texture.png: is a file the scene reads"),
          "-o onto the scene's texture: refused: %s", err_text);
    CHECK(n_png > 8 && test_read_text(DIR "/texture.png", after, sizeof after) == n_png && !memcmp(png, after, n_png),
          "the texture is kept byte for byte");
    remove(DIR "/textured.txt");
    CHECK(run(DIR "/textured.json --points " DIR "/in.txt -o " DIR "/textured.txt", NULL) == 0 &&
              test_line_count(slurp(DIR "/textured.txt")) == 1,
          "a result of another name beside them is written: %s", err_text);
    CHECK(test_count_temporaries(DIR) == 0, "no temporaries left");
    CHECK(run(PLANE " --points " DIR "/folder.txt", NULL) == 1 &&
              strstr(err_text, "folder.txt: is a folder; give the points file"),
          "--points a folder: %s", err_text);
}

typedef struct bad_case {
    const char *what;
    const char *text;      /* the points file */
    const char *must_name; /* text the message must contain */
} bad_case;

static void test_bad_files(void)
{
    static const bad_case cases[] = {
        {"a word", "0 1 0 0 1 0\n# ok\n0 1 zero 0 1 0\n", "bad.txt:3: 'zero' is not a number"},
        {"five numbers", "\n0 1 0 0 1\n", "bad.txt:2: 5 numbers, expected 6"},
        {"seven numbers", "0 1 0 0 1 0 7\n", "bad.txt:1: more than 6 numbers"},
        {"zero normal", "0 1 0 0 1 0\n0 1 0 0 0 0\n", "bad.txt:2: the normal (0 0 0) is zero"},
        {"not finite", "0 1 nan 0 1 0\n", "bad.txt:1: number 3 is not finite"},
        {"far away", "1e20 1 0 0 1 0\n", "bad.txt:1: coordinate 1 (1e+20) lies beyond 1e18"},
        {"a normal too small", "0 1 0 0 1 0\n# c\n0 1 0 1e-50 0 0\n", "bad.txt:3: the normal (1e-50 0 0) is zero or too small"},
        {"no points", "# nothing\n\n", "bad.txt: no points (only comments"},
        {"empty", "", "bad.txt: no points (it is empty)"},
        {"a number run into more text", "0 0.8.1 0 0 1\n", "bad.txt:1: '0.8.1' is not a number"},
        {"decimal commas", "# x y z\n0,5 0,8 1,0\n", "bad.txt:2: some numbers separated by commas, some by spaces"},
        {"an empty CSV field", "0,1,,0,1,0,0\n", "bad.txt:1: an empty field after number 2"},
        {"a byte order mark within", "0 1 0 0 1 0\n\xEF\xBB\xBF" "0 1 0 0 1 0\n",
         "bad.txt:2: '\\xEF\\xBB\\xBF0' is not a number"},
        {"a CSV header", "x,y,z,nx,ny,nz\n0,1,0,0,1,0\n", "bad.txt:1: 'x' is not a number; give 'x y z nx ny nz' "
                                                          "('#' starts a comment)"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        const bad_case *c = &cases[k];
        test_write_file(DIR "/bad.txt", c->text);
        unlink(DIR "/bad-out.txt");
        int st = run(SCENE " --points " DIR "/bad.txt -o " DIR "/bad-out.txt", NULL);
        CHECK(st == 1, "%s: exit %d, expected 1", c->what, st);
        CHECK(strstr(err_text, c->must_name) != NULL, "%s: message names '%s': %s", c->what, c->must_name, err_text);
        CHECK(test_line_count(err_text) == 1, "%s: one line: %s", c->what, err_text);
        CHECK(!test_file_exists(DIR "/bad-out.txt"), "%s: no output file", c->what);
    }
    CHECK(test_count_temporaries(DIR) == 0, "no temporaries left");
    /* A spreadsheet's 'Unicode text' is UTF-16 (little-endian, a byte order mark, tabs): said so. */
    {
        const char *text = "0\t1\t0\t0\t1\t0\r\n";
        FILE *f = fopen(DIR "/utf16.txt", "wb");
        fputc(0xFF, f), fputc(0xFE, f);
        for (const char *c = text; *c; ++c)
            fputc(*c, f), fputc(0, f);
        fclose(f);
        CHECK(run(SCENE " --points " DIR "/utf16.txt", NULL) == 1 && strstr(err_text, "utf16.txt:1: a NUL byte") &&
                  strstr(err_text, "UTF-16") && strstr(err_text, "save it as UTF-8") && test_line_count(err_text) == 1,
              "UTF-16 text: %s", err_text);
    }
    CHECK(run(SCENE " --points " DIR "/missing.txt", NULL) == 1 && strstr(err_text, "missing.txt"),
          "a missing file: exit 1 naming it: %s", err_text);
    CHECK(run(SCENE, NULL) == 2, "no --points: usage error");
    /* The points file given without --points, or the two swapped: the message says what to do. */
    CHECK(run(SCENE " " DIR "/pts.txt", NULL) == 2 && strstr(err_text, "(--points " DIR "/pts.txt)"),
          "a points file without --points: %s", err_text);
    CHECK(run(DIR "/pts.txt --points " SCENE, NULL) == 1 && strstr(err_text, "cornell-box.json:1: '{' is not a number") &&
              strstr(err_text, "the scene comes first") && test_line_count(err_text) == 1,
          "scene and points swapped: %s", err_text);
    CHECK(run(SCENE " --points " DIR "/pts.txt --format xml", NULL) == 2, "unknown format: usage error");
    CHECK(run(SCENE " --points " DIR "/pts.txt --samples 0", NULL) == 2, "--samples 0: usage error");
    CHECK(run(SCENE " --points " DIR "/pts.txt --max-depth 1", NULL) == 2 && strstr(err_text, "max depth 1") &&
              !strstr(err_text, "pts.txt:"),
          "the cache at --max-depth 1: usage error, not blamed on the points file: %s", err_text);
    /* The depth a scene file sets (a render of it takes 1, direct light only): the cache's refusal says where
     * the 1 came from, which the user did not type; --max-depth overrides it. */
    write_plane();
    test_write_file(DIR "/depth1.json", "{\"meshes\": [{\"path\": \"plane.obj\"}], \"environment\": {\"radiance\": "
                                        "[1, 1, 1]}, \"render\": {\"max_depth\": 1}}\n");
    CHECK(run(DIR "/depth1.json --points " DIR "/pts.txt", NULL) == 2 &&
              strstr(err_text, "max depth 1 (direct light only, from the \"render\" settings of ") &&
              strstr(err_text, "depth1.json") && test_line_count(err_text) == 1,
          "the scene file's max depth 1 with the cache: named: %s", err_text);
    CHECK(run(DIR "/depth1.json --points " DIR "/pts.txt --max-depth 2 --rays 64", NULL) == 0,
          "--max-depth 2 overrides it: %s", err_text);
    /* What would fail at the end is found first: an output that cannot be written, a map too large. */
    test_write_file(DIR "/one.txt", "0 1 0 0 1 0\n");
    CHECK(run(SCENE " --points " DIR "/one.txt -o " DIR "/no/such/folder/out.txt", NULL) == 1 &&
              strstr(err_text, "no/such/folder") && test_line_count(err_text) == 1,
          "-o in a missing folder: exit 1 before the work: %s", err_text);
    unlink(DIR "/big.png");
    CHECK(run(SCENE " --grid 0 0 0 5000 1 1 --spacing 1 --map " DIR "/big.png -o " DIR "/big.txt", NULL) == 1 &&
              strstr(err_text, "give a larger --spacing") && !test_file_exists(DIR "/big.png") &&
              !test_file_exists(DIR "/big.txt"),
          "a 5000 x 1 grid's map: exit 1 before the work, nothing written: %s", err_text);
    /* Bounded reading: a line of /dev/zero, an overlong line, more points than --max-points. */
    CHECK(run(SCENE " --points /dev/zero", NULL) == 1 && strstr(err_text, "/dev/zero:1: a line longer than 4096"),
          "/dev/zero: exit 1 at its first line: %s", err_text);
    {
        static char line[5000];
        memset(line, '1', sizeof line - 2);
        line[sizeof line - 2] = '\n';
        test_write_file(DIR "/long.txt", line);
        CHECK(run(SCENE " --points " DIR "/long.txt", NULL) == 1 && strstr(err_text, "long.txt:1: a line longer"),
              "a 5000-byte line: exit 1: %s", err_text);
    }
    /* The limit's edge: a line of 4096 bytes is read, with a Unix or a Windows line end (its CR is the line
     * end's: such a line was refused as longer than 4096 bytes); one of 4097 bytes is not. */
    {
        static char line[4200];
        const char *ends[3] = {"\n", "\r\n", "\n"};
        const int lengths[3] = {4096, 4096, 4097};
        for (int k = 0; k < 3; ++k) {
            memset(line, ' ', sizeof line);
            memcpy(line, "0 1 0 0 1 0", 11);
            snprintf(line + lengths[k], sizeof line - (size_t)lengths[k], "%s", ends[k]);
            test_write_file(DIR "/edge.txt", line);
            int st = run(SCENE " --points " DIR "/edge.txt --integrator pt --samples 16", NULL);
            CHECK(k < 2 ? st == 0 : st == 1 && strstr(err_text, "edge.txt:1: a line longer than 4096 bytes"),
                  "a line of %d bytes and %s: exit %d: %s", lengths[k], k == 1 ? "CRLF" : "LF", st, err_text);
        }
    }
    test_write_file(DIR "/three.txt", "0 1 0 0 1 0\n0 1 0 0 1 0\n0 1 0 0 1 0\n");
    CHECK(run(SCENE " --points " DIR "/three.txt --max-points 2", NULL) == 1 &&
              strstr(err_text, "three.txt:3: more than 2 points (--max-points)"),
          "--max-points 2 with three points: exit 1 naming the line: %s", err_text);
    /* --max-points takes the suffixes of render's limits, either case, its range kept. */
    CHECK(run(SCENE " --points " DIR "/three.txt --max-points 1k --integrator pt --samples 16", NULL) == 0,
          "--max-points 1k: %s", err_text);
    CHECK(run(SCENE " --points " DIR "/three.txt --max-points 4g", NULL) == 2 &&
              strstr(err_text, "--max-points 4g: expected a whole number from 1 to 4294967295") &&
              strstr(err_text, "K, M or G (either case)") && test_line_count(err_text) == 1,
          "--max-points 4g (2^32) is over its range: %s", err_text);
    /* The scene-loading limits of render, named by this command. */
    CHECK(run(SCENE " --points " DIR "/three.txt --max-scene-bytes 10", NULL) == 1 &&
              strstr(err_text, "more than the limit of 10 bytes") && strstr(err_text, "--max-scene-bytes"),
          "--max-scene-bytes 10: the scene refused: %s", err_text);
    CHECK(run(SCENE " --points " DIR "/three.txt --max-mesh-elements", NULL) == 2 &&
              strstr(err_text, "irrcache points: --max-mesh-elements needs a value"),
          "--max-mesh-elements without a value: usage error of points: %s", err_text);
    /* An option of the other estimator is refused, not ignored: --samples with the cache (the default) ran
     * 256 light samples while the user asked for 4096 paths. */
    static const char *const other[][2] = {
        {"--samples 4096", "--samples is the path tracer's; add --integrator pt"},
        {"--integrator pt --light-samples 64", "--light-samples is the cache's; add --integrator ic"},
        {"--integrator pt --accuracy 0.1", "--accuracy is the cache's; add --integrator ic"},
        {"--integrator pt --rays=64", "--rays is the cache's; add --integrator ic"},
    };
    for (size_t k = 0; k < sizeof other / sizeof other[0]; ++k) {
        char args[1024];
        snprintf(args, sizeof args, SCENE " --points " DIR "/three.txt %s", other[k][0]);
        CHECK(run(args, NULL) == 2 && strstr(err_text, other[k][1]) && test_line_count(err_text) == 1,
              "%s: usage error: %s", other[k][0], err_text);
    }
    /* The options shared with render take render's values and checks, named by this command. */
    CHECK(run(SCENE " --points " DIR "/three.txt --accuracy 0", NULL) == 2 &&
              strstr(err_text, "irrcache points: --accuracy 0: expected a number from 0.001 to 100"),
          "--accuracy 0: render's range, named by points: %s", err_text);
    CHECK(run(SCENE " --points " DIR "/three.txt --rays=4", NULL) == 2 &&
              strstr(err_text, "irrcache points: --rays 4: expected an integer from 16 to 10000000"),
          "--rays=4: render's range, its = form: %s", err_text);
    CHECK(run(SCENE " --points " DIR "/three.txt --threads=1 --seed 18446744073709551615 --rays 64 --accuracy 0.5",
              NULL) == 0,
          "--threads=1, a seed of 2^64 - 1 (render's range): %s", err_text);
}

int main(void)
{
    mkdir(DIR, 0755);
    test_outputs();
    test_accepted_inputs();
    test_round_trip();
    test_outputs_refused();
    test_bad_files();
    test_daylight_factor();
    test_grid_map();
    TEST_MAIN_END();
}
