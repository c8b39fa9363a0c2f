/*
 * test_scene_big.c — a large scene file loads in time linear in its size (issue "Hardening", item 2):
 * the line of each key is counted on from the previous look-up instead of from the start of the file,
 * and a key written with escapes ("typ\u0065") is still found where it is. Checked by counting the bytes
 * the look-ups examine (no wall-time assertion), and by loading a 20,000-light scene whose last light
 * has an error: the message names its line.
 */
#include "scene/json_context.h"
#include "scene/scene.h"
#include "test_util.h"

#include <string.h>

#define N_OBJECTS 20000
#define BIG IC_TEST_TMP "/scene_big.json"

/* Lines per light in the generated text: "{", type, position, intensity, "},". */
enum { LINES_PER = 5 };

static char *light_list(int n, int escaped, size_t *len)
{
    size_t cap = (size_t)n * 160 + 64;
    char *t = malloc(cap), *p = t;
    p += sprintf(p, "{\n\"lights\": [\n");
    for (int i = 0; i < n; ++i)
        p += sprintf(p, " {\n  \"%s\": \"point\",\n  \"position\": [0, %d, 0],\n  \"intensity\": 1\n }%s\n",
                     escaped ? "typ\\u0065" : "type", i, i + 1 < n ? "," : "");
    p += sprintf(p, "]\n}\n");
    *len = (size_t)(p - t);
    return t;
}

/* Walks the lights as the loader does (object start, peek "type", each key in order). */
static void walk(int escaped)
{
    size_t len;
    char *text = light_list(N_OBJECTS, escaped, &len);
    json_ctx c;
    memset(&c, 0, sizeof c);
    c.text = text;
    c.len = len;
    c.line = 1;
    int bad = 0;
    CHECK(ic_json_locate_key(&c, "lights") == 2, "the section's line");
    for (int i = 0; i < N_OBJECTS; ++i) {
        int first = 3 + LINES_PER * i;
        bad += ic_json_locate_object_start(&c) != first;
        bad += ic_json_peek_key_line(&c, "type") != first + 1;
        bad += ic_json_locate_key(&c, "type") != first + 1;
        bad += ic_json_locate_key(&c, "position") != first + 2;
        bad += ic_json_locate_key(&c, "intensity") != first + 3;
    }
    CHECK(bad == 0, "%s keys: %d look-ups gave a wrong line", escaped ? "escaped" : "plain", bad);
    /* Each byte is examined a bounded number of times: the peek, the search and the line count. */
    CHECK(c.scanned <= 4 * len, "%s keys: %zu bytes examined for a %zu-byte text (linear: at most 4x)",
          escaped ? "escaped" : "plain", c.scanned, len);
    /* Going back (each section restarts at its own key) counts only the distance. */
    size_t before = c.scanned;
    CHECK(ic_json_line_of(&c, 0) == 1 && ic_json_line_of(&c, len) == 3 + LINES_PER * N_OBJECTS + 2,
          "first and last line");
    CHECK(c.scanned - before <= 2 * len, "back and forth once: %zu bytes", c.scanned - before);
    free(text);
}

/* A scene of N_OBJECTS point lights (the last of type last_type) over a small mesh. */
static void write_scene(const char *last_type)
{
    FILE *f = fopen(BIG, "w");
    CHECK(f != NULL, "write %s", BIG);
    if (!f)
        return;
    fprintf(f, "{\n\"meshes\": [{\"path\": \"%s\"}],\n\"lights\": [\n", IC_SOURCE_DIR "/tests/scenes/quad_light.obj");
    for (int i = 0; i < N_OBJECTS; ++i)
        fprintf(f, " {\n  \"type\": \"%s\",\n  \"position\": [0, %d, 0],\n  \"intensity\": 1\n }%s\n",
                i + 1 < N_OBJECTS ? "point" : last_type, i, i + 1 < N_OBJECTS ? "," : "");
    fprintf(f, "]\n}\n");
    fclose(f);
}

int main(void)
{
    walk(0);
    walk(1);

    /* The whole loader on a 20,000-light file whose last light has an unknown type; the same file
     * without the error loads, with every light. */
    ic_scene *scene = NULL;
    ic_error err;
    memset(&err, 0, sizeof err);
    ic_scene_load_options opt = {0};
    opt.allow_outside_paths = 1; /* the file in IC_TEST_TMP names a mesh in tests/scenes */
    write_scene("laser");
    ic_result r = ic_scene_load(BIG, &opt, &scene, &err);
    char want[64];
    snprintf(want, sizeof want, "scene_big.json:%d:", 4 + LINES_PER * (N_OBJECTS - 1) + 1);
    CHECK(r == IC_ERR_INVALID_ARG && strstr(err.message, want) && strstr(err.message, "'laser'"),
          "the last light's error names its line %s: %s", want, err.message);
    CHECK(scene == NULL, "no scene on failure");
    write_scene("point");
    r = ic_scene_load(BIG, &opt, &scene, &err);
    CHECK(r == IC_OK && scene, "the corrected file loads: %s", r == IC_OK ? "" : err.message);
    if (scene)
        ic_scene_free(scene);
    TEST_MAIN_END();
}
