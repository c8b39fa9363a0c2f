/*
 * test_cli_rad.c — `irrcache render model.rad --view model.vf` from the command line: the Cornell box
 * renders with its view's resolution, and from a fisheye view; a "!" command line and a bad view each give a non-zero exit and one
 * line on stderr naming file:line (and the command, which is never run: the file it would create stays
 * absent); --view with a JSON scene is refused.
 */
#include "test_util.h"
#include "test_files.h"
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
    TEST_MAIN_END();
}
