/*
 * test_cli_rad.c — `irrcache render model.rad --view model.vf` from the command line: the Cornell box
 * renders with its view's resolution, and from a fisheye view; a "!" command line and a bad view each give a non-zero exit and one
 * line on stderr naming file:line (and the command, which is never run: the file it would create stays
 * absent); --view with a JSON scene is refused; `irrcache points` under gensky -c's pasted output reads the JSON
 * scene's cie-overcast sky of the same zenith and ground radiance, but for the horizon blending of Radiance's
 * skybright.cal (−0.14 % up, +0.3 % down, integrated in test_rad_sky.h), within the two results' σ.
 */
#include "test_util.h"
#include "test_files.h"
#include "test_rad_sky.h"
#include "test_render_util.h"

#include <string.h>
#include <sys/stat.h>

#define CLI IC_CLI_PATH
#define ERR IC_TEST_TMP "/cli_rad_stderr.txt"

static char err_text[8192];

/* Runs `irrcache render ARGS` (stderr captured); the exit status, or -1 if it crashed. */
static int render(const char *args)
{
    return test_run_quiet(ERR, err_text, sizeof err_text, "%s render %s", CLI, args);
}

static int one_line(void) { return strchr(err_text, '\n') == strrchr(err_text, '\n') && err_text[0]; }

/* `irrcache points SCENE --points POINTS` (path tracer, 8192 samples): each line's lux and sigma into lux[] and
 * sigma[] (two lines); the exit status. */
static int points(const char *scene, const char *pts, double lux[2], double sigma[2])
{
    const char *out = IC_TEST_TMP "/cli_rad_points.txt";
    int rc = test_run_quiet(ERR, err_text, sizeof err_text, "%s points %s --points %s --integrator pt --samples 8192 --threads 2 -o %s",
                            CLI, scene, pts, out);
    char text[1024];
    test_read_text(out, text, sizeof text);
    double e[3];
    const char *line = text;
    for (int k = 0; k < 2; ++k) {
        lux[k] = sigma[k] = -1.0;
        if (line && sscanf(line, "%lf %lf %lf %lf %lf", &e[0], &e[1], &e[2], &lux[k], &sigma[k]) != 5)
            lux[k] = -1.0;
        line = line ? strchr(line, '\n') : NULL;
        line = line ? line + 1 : NULL;
    }
    return rc;
}

/* The pasted output of gensky -c (zenith 31.6 W/(sr m2), ground 4.91) against the JSON scene's cie-overcast sky
 * of the same zenith radiance and ground (ρ 7/9 L_z = 4.91), one sensor up and one down each. */
static void test_pasted_gensky(void)
{
    const double A[8] = {0, 2, 31.6, 4.91}; /* A5–A7 unused by the overcast sky */
    char text[2048];
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "3 2 3.16e+01 4.91e+00", "1 1 1", "1 1 1");
    test_write_file(IC_TEST_TMP "/cli_rad_sky.rad", text);
    test_write_file(IC_TEST_TMP "/cli_rad_sky.pts", "0 0 1 0 0 1\n0 0 1 0 0 -1\n");
    /* JSON needs a mesh: a millimetre triangle a kilometre away */
    test_write_file(IC_TEST_TMP "/cli_rad_speck.obj", "v 1000 0.5 1000\nv 1000.001 0.5 1000\nv 1000 0.501 1000\nf 1 2 3\n");
    snprintf(text, sizeof text,
             "{\"meshes\": [{\"path\": \"cli_rad_speck.obj\"}],\n \"environment\": {\"sky\": \"cie-overcast\", "
             "\"zenith_radiance\": 31.6, \"ground_reflectance\": %.17g}}\n",
             A[3] / (7.0 / 9.0 * A[2]));
    test_write_file(IC_TEST_TMP "/cli_rad_sky.json", text);
    test_write_file(IC_TEST_TMP "/cli_rad_sky_json.pts", "0 1 0 0 1 0\n0 1 0 0 -1 0\n");
    double rad[2], rad_s[2], json[2], json_s[2];
    int rc = points(IC_TEST_TMP "/cli_rad_sky.rad", IC_TEST_TMP "/cli_rad_sky.pts", rad, rad_s);
    CHECK(rc == 0 && rad[1] > 0.0 && !err_text[0], "points under the pasted gensky sky: exit %d, %s", rc, err_text);
    rc = points(IC_TEST_TMP "/cli_rad_sky.json", IC_TEST_TMP "/cli_rad_sky_json.pts", json, json_s);
    CHECK(rc == 0 && json[1] > 0.0, "points under the JSON sky: exit %d, %s", rc, err_text);
    for (int k = 0; k < 2; ++k) {
        double blend = 179.0 * test_overcast_blend_share(A, k == 0), sigma = sqrt(rad_s[k] * rad_s[k] + json_s[k] * json_s[k]);
        printf("points %s: pasted gensky -c %.2f +- %.2f lux, JSON cie-overcast %.2f +- %.2f lux, difference %+.2f, "
               "skybright.cal's horizon blending %+.2f\n",
               k ? "down" : "up", rad[k], rad_s[k], json[k], json_s[k], rad[k] - json[k], blend);
        CHECK(fabs(rad[k] - json[k] - blend) <= 3.0 * sigma + 1e-4 * json[k],
              "%s: the pasted sky reads the JSON sky but for the horizon blending, within 3 sigma", k ? "down" : "up");
    }
    /* --daylight-factor under the pasted sky (it was refused: "needs a CIE overcast sky"): the open upward
     * sensor reads 100 % within 3 sigma, its lux over the sky's unobstructed horizontal illuminance */
    const char *out = IC_TEST_TMP "/cli_rad_df.txt";
    rc = test_run_quiet(ERR, err_text, sizeof err_text,
                        "%s points %s --points %s --integrator pt --samples 4096 --threads 2 --daylight-factor -o %s", CLI,
                        IC_TEST_TMP "/cli_rad_sky.rad", IC_TEST_TMP "/cli_rad_sky.pts", out);
    char df_text[1024];
    test_read_text(out, df_text, sizeof df_text);
    double v[7] = {0};
    CHECK(rc == 0 && sscanf(df_text, "%lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6]) == 7 &&
              fabs(v[5] - 100.0) <= 3.0 * v[6] + 1e-3,
          "--daylight-factor under gensky -c's sky: the open sensor reads %g +- %g %% (exit %d, %s)", v[5], v[6], rc,
          err_text);
}

int main(void)
{
    const char *png = IC_TEST_TMP "/cli_rad.png";
    remove(png);
    int rc = render(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.rad --view " IC_SOURCE_DIR
                    "/scenes/cornell-box/cornell-box.vf --width 24 --height 48 --spp 1 --threads 2 -o " IC_TEST_TMP
                    "/cli_rad.png");
    struct stat st;
    CHECK(rc == 0 && stat(png, &st) == 0, "the Cornell box renders from its view: exit %d, %s", rc, err_text);

    const char *marker = IC_TEST_TMP "/cli_rad_ran";
    remove(marker);
    char text[512];
    snprintf(text, sizeof text, "void plastic p 0 0 5 .5 .5 .5 0 0\n\n!touch %s\n", marker);
    test_write_file(IC_TEST_TMP "/cli_rad_cmd.rad", text);
    rc = render(IC_TEST_TMP "/cli_rad_cmd.rad -o " IC_TEST_TMP "/cli_rad_cmd.png");
    CHECK(rc != 0 && one_line() && strstr(err_text, "cli_rad_cmd.rad:3:") && strstr(err_text, "!touch") &&
              stat(marker, &st) != 0,
          "a command line: refused (exit %d), named with file:line, never run: %s", rc, err_text);

    test_write_file(IC_TEST_TMP "/cli_rad_fish.vf", "rpict -vth -vp 0 1 3 -vd 0 0 -1 -vu 0 1 0 -vh 180 -vv 180\n");
    rc = render(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.rad --view " IC_TEST_TMP "/cli_rad_fish.vf --width 16 "
                "--height 16 --spp 1 --threads 2 -o " IC_TEST_TMP "/cli_rad_fish.png");
    CHECK(rc == 0, "a fisheye view renders: exit %d, %s", rc, err_text);
    test_write_file(IC_TEST_TMP "/cli_rad.vf", "rpict -vth -vp 0 1 3 -vd 0 0 -1 -vu 0 1 0 -vh 200\n");
    rc = render(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.rad --view " IC_TEST_TMP "/cli_rad.vf -o " IC_TEST_TMP
                "/cli_rad_vf.png");
    CHECK(rc != 0 && one_line() && strstr(err_text, "cli_rad.vf:1:") && strstr(err_text, "hemispherical"),
          "a fisheye view wider than 180 degrees: refused (exit %d): %s", rc, err_text);

    rc = render(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json --view " IC_SOURCE_DIR
                "/scenes/cornell-box/cornell-box.vf -o " IC_TEST_TMP "/cli_rad_json.png");
    CHECK(rc != 0 && one_line() && strstr(err_text, "--view"), "--view with a JSON scene: refused (exit %d): %s", rc,
          err_text);
    test_pasted_gensky();
    TEST_MAIN_END();
}
