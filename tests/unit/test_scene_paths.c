/*
 * test_scene_paths.c — files a scene names stay inside the scene file's folder tree and the shared scenes
 * folder unless allow_outside_paths (--allow-outside-paths) is set (issue "Hardening": "a glTF buffer URI
 * may point anywhere on disk"; docs/scene-format.md, "Paths"): a mesh, an MTL file, a glTF buffer, a
 * texture and an environment map outside (JSON; a Mitsuba envmap, a Radiance mesh) are refused with one
 * line naming the scene file (and line), the
 * file and the option; a symbolic link inside that points outside is refused (real paths are compared);
 * the same scenes load with the option; "shared:" paths still load. The files a scene read are listed
 * (ic_scene_file), each once, for the command to keep its outputs off them.
 *
 * Everything is written under IC_TEST_TMP/scene_paths:
 *   outside.obj outside.mtl x.bin outside.pfm     the files outside
 *   scene/                                        the scene's folder (every scene file lies here)
 *   scene/m/                                      glTF files, in a folder below the scene's
 *   shared/quad.obj quad.mtl                      the shared scenes folder (shared_scenes_dir)
 */
#include "scene/scene.h"
#include "test_util.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#define SCENES IC_SOURCE_DIR "/tests/scenes/"
#define T IC_TEST_TMP "/scene_paths"
#define CLI IC_CLI_PATH

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL, "write %s: %s", path, strerror(errno));
    if (!f)
        return;
    fputs(text, f);
    fclose(f);
}

static void copy_file(const char *from, const char *to)
{
    FILE *in = fopen(from, "rb"), *out = fopen(to, "wb");
    CHECK(in && out, "copy %s to %s", from, to);
    if (in && out) {
        char buf[4096];
        size_t n;
        while ((n = fread(buf, 1, sizeof buf, in)) > 0)
            fwrite(buf, 1, n, out);
    }
    if (in)
        fclose(in);
    if (out)
        fclose(out);
}

/* A one-triangle glTF whose buffer (three float vertices, then three uint16 indices) is at `uri`. */
static void write_gltf(const char *path, const char *uri)
{
    char text[2048];
    snprintf(text, sizeof text,
             "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}],\n"
             " \"nodes\": [{\"mesh\": 0}],\n"
             " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1}]}],\n"
             " \"buffers\": [{\"uri\": \"%s\", \"byteLength\": 44}],\n"
             " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
             "                   {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 6}],\n"
             " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\",\n"
             "                  \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
             "                 {\"bufferView\": 1, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\"}]}\n",
             uri);
    write_text(path, text);
}

static void write_buffer(const char *path)
{
    const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const unsigned short idx[4] = {0, 1, 2, 0};
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL, "write %s", path);
    if (!f)
        return;
    fwrite(v, sizeof v, 1, f);
    fwrite(idx, sizeof idx, 1, f);
    fclose(f);
}

/* Loads path; returns the result and leaves the message in err. */
static ic_result try_load(const char *path, int allow, const char *shared, ic_error *err)
{
    ic_scene_load_options opt;
    memset(&opt, 0, sizeof opt);
    opt.allow_outside_paths = allow;
    opt.shared_scenes_dir = shared;
    ic_scene *s = NULL;
    memset(err, 0, sizeof *err);
    ic_result r = ic_scene_load(path, &opt, &s, err);
    CHECK((r == IC_OK) == (s != NULL), "%s: a scene exactly on success", path);
    ic_scene_free(s);
    return r;
}

/* Refused without the option (one line naming each of up to three strings and the option), loads with it. */
static void expect_outside(const char *path, const char *s1, const char *s2, const char *s3)
{
    ic_error err;
    ic_result r = try_load(path, 0, NULL, &err);
    CHECK(r == IC_ERR_INVALID_ARG, "%s: refused, got %s (%s)", path, ic_result_name(r), err.message);
    const char *want[4] = {s1, s2, s3, "--allow-outside-paths"};
    for (int i = 0; i < 4; ++i)
        if (want[i])
            CHECK(strstr(err.message, want[i]) != NULL, "%s: message lacks '%s': %s", path, want[i], err.message);
    CHECK(strchr(err.message, '\n') == NULL, "%s: one line", path);
    CHECK(strstr(err.message, "outside") != NULL, "%s: says it is outside: %s", path, err.message);
    r = try_load(path, 1, NULL, &err);
    CHECK(r == IC_OK, "%s: loads with allow_outside_paths: %s", path, err.message);
}

static void expect_loads(const char *path, const char *shared)
{
    ic_error err;
    ic_result r = try_load(path, 0, shared, &err);
    CHECK(r == IC_OK, "%s: loads: %s", path, err.message);
}

/* Loads path (allowed outside its folder, with the view file view or NULL) and checks that the files it
 * read (ic_scene_file) are exactly those of want (NULL-terminated, compared as real paths), each once. */
static void expect_files(const char *path, const char *view, const char *const *want)
{
    ic_scene_load_options opt;
    memset(&opt, 0, sizeof opt);
    opt.allow_outside_paths = 1;
    opt.view = view;
    ic_scene *s = NULL;
    ic_error err;
    CHECK(ic_scene_load(path, &opt, &s, &err) == IC_OK, "%s loads: %s", path, err.message);
    uint32_t n = 0;
    for (; want[n]; ++n) {
        char real[PATH_MAX] = "";
        CHECK(realpath(want[n], real) != NULL, "%s exists", want[n]);
        int found = 0;
        for (uint32_t k = 0; k < ic_scene_file_count(s); ++k)
            found += !strcmp(ic_scene_file(s, k), real);
        CHECK(found == 1, "%s: %s is among the files it read, once (%d)", path, real, found);
    }
    CHECK(ic_scene_file_count(s) == n, "%s: %u files read, expected %u", path, ic_scene_file_count(s), n);
    char scene_real[PATH_MAX] = "";
    CHECK(realpath(path, scene_real) && ic_scene_file(s, 0) && !strcmp(ic_scene_file(s, 0), scene_real) &&
              ic_scene_file(s, n) == NULL,
          "%s: the scene file first, no file past the count", path);
    ic_scene_free(s);
}

/* The command: refused with exit 1 and the option named, rendered with --allow-outside-paths. */
static void check_cli(void)
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "%s render %s -o %s --width 4 --height 4 --spp 1 -q 2>%s", CLI, T "/scene/mesh.json",
             T "/out.pfm", T "/stderr.txt");
    int st = system(cmd);
    char text[2048] = "";
    FILE *f = fopen(T "/stderr.txt", "r");
    if (f) {
        size_t n = fread(text, 1, sizeof text - 1, f);
        text[n] = '\0';
        fclose(f);
    }
    CHECK(st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 1, "CLI refuses the scene with exit 1: %s", text);
    CHECK(strstr(text, "mesh.json:2:") && strstr(text, "--allow-outside-paths"), "CLI names the line and the "
          "option: %s", text);
    CHECK(access(T "/out.pfm", F_OK) != 0, "CLI writes nothing");
    snprintf(cmd, sizeof cmd, "%s render %s -o %s --width 4 --height 4 --spp 1 -q --allow-outside-paths 2>%s", CLI,
             T "/scene/mesh.json", T "/out.pfm", T "/stderr.txt");
    st = system(cmd);
    CHECK(st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 0, "CLI renders with --allow-outside-paths");
    CHECK(access(T "/out.pfm", F_OK) == 0, "CLI wrote the image");
}

/* A file name with a newline, a carriage return and an escape in it: the message quoting it stays on one
 * line (the control bytes written as \xNN), so that "file:line: what; what to do" is still one line. */
static void test_control_bytes_in_name(void)
{
    const char *path = T "/bad\nname\r\x1b.json";
    write_text(path, "{\n  \"meshes\": [ { \"path\": 7 } ]\n}\n");
    ic_scene *scene = NULL;
    ic_scene_load_options lo = {0};
    ic_error err = {0};
    ic_result r = ic_scene_load(path, &lo, &scene, &err);
    CHECK(r != IC_OK && !strchr(err.message, '\n') && !strchr(err.message, '\r') && !strchr(err.message, 0x1b) &&
              strstr(err.message, "bad\\x0aname\\x0d\\x1b.json:2:"),
          "a file name with control bytes: \"%s\"", err.message);
    ic_scene_free(scene);

    /* A warning quoting such a name is one line as well (the warnings are one a line). */
    const char *obj = T "/bad\nwarn\x1b.obj";
    write_text(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n");
    scene = NULL;
    r = ic_scene_load(obj, &lo, &scene, &err);
    const char *w = r == IC_OK ? ic_scene_warnings(scene) : "";
    const char *nl = strchr(w, '\n');
    CHECK(r == IC_OK && nl && nl[1] == '\0' && !strchr(w, 0x1b) && strstr(w, "bad\\x0awarn\\x1b.obj") &&
              strstr(w, "zero area"),
          "a warning naming a file with control bytes is one line (%s): \"%s\"", err.message, w);
    ic_scene_free(scene);
}

int main(void)
{
    CHECK(system("rm -rf '" T "' && mkdir -p '" T "/scene/m' '" T "/shared'") == 0, "make %s", T);
    test_control_bytes_in_name();

    /* the files outside the scene's folder */
    copy_file(SCENES "quad_light.obj", T "/outside.obj"); /* mtllib quad_light.mtl */
    copy_file(SCENES "quad_light.mtl", T "/quad_light.mtl");
    copy_file(SCENES "quad_light.mtl", T "/outside.mtl");
    copy_file(SCENES "checker2x2.pfm", T "/outside.pfm");
    write_buffer(T "/x.bin");

    /* a mesh: relative, absolute, and through a symbolic link inside the folder */
    write_text(T "/scene/mesh.json", "{\n  \"meshes\": [ { \"path\": \"../outside.obj\" } ]\n}\n");
    expect_outside(T "/scene/mesh.json", "mesh.json:2:", "mesh '../outside.obj'", T "/outside.obj");
    write_text(T "/scene/absolute.json", "{\n  \"meshes\": [ { \"path\": \"" T "/outside.obj\" } ]\n}\n");
    expect_outside(T "/scene/absolute.json", "absolute.json:2:", T "/outside.obj", NULL);
    CHECK(symlink("../outside.obj", T "/scene/link.obj") == 0, "symlink: %s", strerror(errno));
    write_text(T "/scene/link.json", "{\n  \"meshes\": [ { \"path\": \"link.obj\" } ]\n}\n");
    expect_outside(T "/scene/link.json", "link.json:2:", "'link.obj'", T "/outside.obj");
    expect_outside(T "/scene/link.obj", "link.obj", T "/outside.obj", NULL); /* a bare mesh: its folder */

    /* an MTL file named by a mesh inside, and an MTL file's texture */
    copy_file(SCENES "plain_quad.obj", T "/scene/mtl.obj");
    CHECK(system("sed -i 's|^mtllib .*|mtllib ../outside.mtl|' '" T "/scene/mtl.obj'") == 0, "edit mtllib");
    write_text(T "/scene/mtl.json", "{\n  \"meshes\": [\n    { \"path\": \"mtl.obj\" } ]\n}\n");
    expect_outside(T "/scene/mtl.json", "mtl.json:3:", "MTL file", T "/outside.mtl");
    copy_file(SCENES "plain_quad.obj", T "/scene/tex.obj");
    CHECK(system("sed -i 's|^mtllib .*|mtllib tex.mtl|' '" T "/scene/tex.obj'") == 0, "edit mtllib");
    write_text(T "/scene/tex.mtl", "newmtl checker\nKd 0.5 0.5 0.5\nmap_Kd ../outside.pfm\n");
    write_text(T "/scene/tex.json", "{\n  \"meshes\": [ { \"path\": \"tex.obj\" } ]\n}\n");
    expect_outside(T "/scene/tex.json", "tex.json:2:", "texture", T "/outside.pfm");

    /* a texture and an environment map named by the scene file */
    copy_file(SCENES "plain_quad.obj", T "/scene/plain_quad.obj");
    copy_file(SCENES "plain_quad.mtl", T "/scene/plain_quad.mtl");
    copy_file(SCENES "checker2x2.pfm", T "/scene/checker2x2.pfm");
    write_text(T "/scene/kd.json", "{\n  \"meshes\": [ { \"path\": \"plain_quad.obj\" } ],\n  \"materials\": {\n"
                                   "    \"checker\": { \"kd_texture\": \"../outside.pfm\" } }\n}\n");
    expect_outside(T "/scene/kd.json", "kd.json:4:", "texture '../outside.pfm'", T "/outside.pfm");
    write_text(T "/scene/quad.json", "{\n  \"meshes\": [ { \"path\": \"plain_quad.obj\" } ]\n}\n");
    expect_loads(T "/scene/quad.json", NULL); /* its texture beside it */
    write_text(T "/scene/env.json", "{\n  \"meshes\": [ { \"path\": \"m/inside.gltf\" } ],\n"
                                    "  \"environment\": { \"map\": \"../outside.pfm\" }\n}\n");

    /* glTF: a buffer URI that leaves the folder tree, from a scene and as a bare mesh; one inside loads */
    write_gltf(T "/scene/m/escape.gltf", "../../x.bin");
    write_text(T "/scene/gltf.json", "{\n  \"meshes\": [ { \"path\": \"m/escape.gltf\" } ]\n}\n");
    expect_outside(T "/scene/gltf.json", "gltf.json:2:", "escape.gltf", T "/x.bin");
    expect_outside(T "/scene/m/escape.gltf", "escape.gltf", T "/x.bin", NULL);
    write_buffer(T "/scene/m/inside.bin");
    write_gltf(T "/scene/m/inside.gltf", "inside.bin");
    write_text(T "/scene/inside.json", "{\n  \"meshes\": [ { \"path\": \"m/inside.gltf\" } ]\n}\n");
    expect_loads(T "/scene/inside.json", NULL);
    expect_loads(T "/scene/m/inside.gltf", NULL);
    expect_outside(T "/scene/env.json", "env.json:3:", "environment map '../outside.pfm'", T "/outside.pfm");

    /* The other scene formats: a Mitsuba envmap and a Radiance mesh outside the folder tree. */
    write_text(T "/scene/env.xml", "<scene version=\"0.6.0\">\n"
                                   "  <shape type=\"obj\"><string name=\"filename\" value=\"plain_quad.obj\"/></shape>\n"
                                   "  <emitter type=\"envmap\">\n"
                                   "    <string name=\"filename\" value=\"../outside.pfm\"/>\n"
                                   "  </emitter>\n</scene>\n");
    expect_outside(T "/scene/env.xml", "env.xml:3:", "environment map", T "/outside.pfm");
    write_text(T "/scene/mesh.rad", "void light glow\n0\n0\n3 1 1 1\n\nvoid mesh box\n1 ../outside.obj\n0\n0\n");
    expect_outside(T "/scene/mesh.rad", "mesh.rad:", "mesh", T "/outside.obj");

    /* shared: paths resolve outside the scene's folder and load; a file beside the shared folder does not */
    copy_file(SCENES "quad_light.obj", T "/shared/quad.obj");
    copy_file(SCENES "quad_light.mtl", T "/shared/quad_light.mtl");
    write_text(T "/scene/shared.json", "{\n  \"meshes\": [ { \"path\": \"shared:quad.obj\" } ]\n}\n");
    expect_loads(T "/scene/shared.json", T "/shared");
    write_text(T "/scene/shared_escape.json", "{\n  \"meshes\": [ { \"path\": \"shared:../outside.obj\" } ]\n}\n");
    {
        ic_error err;
        ic_result r = try_load(T "/scene/shared_escape.json", 0, T "/shared", &err);
        CHECK(r == IC_ERR_INVALID_ARG && strstr(err.message, "shared_escape.json:2:") &&
                  strstr(err.message, T "/shared") && strstr(err.message, "--allow-outside-paths"),
              "shared:../ leaves the shared folder: %s", err.message);
    }
    /* the repository's own fixture that names the Cornell box two folders up */
    {
        ic_error err;
        ic_result r = try_load(SCENES "transformed.json", 0, NULL, &err);
        CHECK(r == IC_ERR_INVALID_ARG && strstr(err.message, "transformed.json:3:"),
              "transformed.json needs the option: %s", err.message);
    }

    /* The files each scene read, which the command keeps its outputs off: the scene file, its meshes, their
     * MTL files and buffers, textures (named by an MTL file or by the scene), environment maps, a view file. */
    expect_files(T "/scene/kd.json", NULL,
                 (const char *const[]){T "/scene/kd.json", T "/scene/plain_quad.obj", T "/scene/plain_quad.mtl",
                                       T "/scene/checker2x2.pfm", T "/outside.pfm", NULL});
    expect_files(T "/scene/m/inside.gltf", NULL,
                 (const char *const[]){T "/scene/m/inside.gltf", T "/scene/m/inside.bin", NULL});
    expect_files(T "/scene/env.json", NULL,
                 (const char *const[]){T "/scene/env.json", T "/scene/m/inside.gltf", T "/scene/m/inside.bin",
                                       T "/outside.pfm", NULL});
    expect_files(T "/scene/env.xml", NULL,
                 (const char *const[]){T "/scene/env.xml", T "/scene/plain_quad.obj", T "/scene/plain_quad.mtl",
                                       T "/scene/checker2x2.pfm", T "/outside.pfm", NULL});
    write_text(T "/scene/view.vf", "rvu -vtv -vp 0 -5 0 -vd 0 1 0 -vu 0 0 1 -vh 45 -vv 45\n");
    expect_files(T "/scene/mesh.rad", T "/scene/view.vf",
                 (const char *const[]){T "/scene/mesh.rad", T "/outside.obj", T "/quad_light.mtl", T "/scene/view.vf",
                                       NULL});

    check_cli();
    TEST_MAIN_END();
}
