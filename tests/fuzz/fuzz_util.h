/*
 * fuzz_util.h — what every harness in tests/fuzz/ shares: one scratch folder per process, files written
 * into it, and the companion files a scene or mesh may name (a mesh with its MTL, a texture).
 *
 * Each harness defines LLVMFuzzerTestOneInput; it is linked either with libFuzzer (IC_FUZZ=ON, clang) or
 * with replay_main.c (the normal build's fuzz_replay_* tests). The folder is made once (mkdtemp under
 * $TMPDIR, else /tmp) and removed at exit; a harness writes the input under a fixed name in it, so a run
 * is deterministic: the same bytes give the same calls.
 */
#ifndef IC_FUZZ_UTIL_H
#define IC_FUZZ_UTIL_H

#include <dirent.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char fuzz_dir_path[512];

static inline void fuzz_dir_remove(void)
{
    if (!fuzz_dir_path[0])
        return;
    DIR *d = opendir(fuzz_dir_path);
    if (d) {
        struct dirent *e;
        char p[1024];
        while ((e = readdir(d)) != NULL) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            snprintf(p, sizeof p, "%s/%s", fuzz_dir_path, e->d_name);
            unlink(p);
        }
        closedir(d);
    }
    rmdir(fuzz_dir_path);
    fuzz_dir_path[0] = '\0';
}

/* Writes size bytes to path (a failure aborts: the harness cannot go on without its file). */
static inline void fuzz_write_path(const char *path, const void *data, size_t size)
{
    FILE *fp = fopen(path, "wb");
    if (!fp || (size && fwrite(data, 1, size, fp) != size) || fclose(fp) != 0) {
        fprintf(stderr, "fuzz: cannot write %s\n", path);
        abort();
    }
}

/* The scratch folder (made on first use). */
static const char *fuzz_dir(void)
{
    if (!fuzz_dir_path[0]) {
        const char *tmp = getenv("TMPDIR");
        if (!tmp || !*tmp)
            tmp = "/tmp";
        snprintf(fuzz_dir_path, sizeof fuzz_dir_path, "%s/irrcache-fuzz-XXXXXX", tmp);
        if (!mkdtemp(fuzz_dir_path)) {
            fprintf(stderr, "fuzz: cannot make a folder under %s\n", tmp);
            abort();
        }
        atexit(fuzz_dir_remove);
    }
    return fuzz_dir_path;
}

/* Writes data as <scratch>/name; path receives the full path (cap bytes). */
static inline void fuzz_write(const char *name, const void *data, size_t size, char *path, size_t cap)
{
    snprintf(path, cap, "%s/%s", fuzz_dir(), name);
    fuzz_write_path(path, data, size);
}

/* Companion files a scene or a mesh under test may name (relative to the scratch folder):
 *   quad.obj + quad.mtl  a lit quad (material "light" emits, "floor" is textured with checker.pfm)
 *   checker.pfm          a 2x2 colour PFM (a texture or an environment map)
 *   tri.bin, tri.gltf    a glTF buffer (one triangle: 3 float3 positions, 3 u16 indices) and a glTF naming it */
static inline void fuzz_companions(void)
{
    static int done = 0;
    if (done)
        return;
    done = 1;
    static const char quad_obj[] =
        "mtllib quad.mtl\n"
        "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
        "v -0.2 1.5 -0.2\nv 0.2 1.5 -0.2\nv 0.2 1.5 0.2\nv -0.2 1.5 0.2\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\nvn 0 -1 0\n"
        "usemtl floor\nf 1/1/1 4/4/1 3/3/1 2/2/1\n"
        "usemtl light\nf 5//2 6//2 7//2 8//2\n";
    static const char quad_mtl[] =
        "newmtl floor\nKd 0.8 0.8 0.8\nKs 0.1 0.1 0.1\nNs 20\nmap_Kd checker.pfm\n"
        "newmtl light\nKd 0 0 0\nKe 5 5 5\n";
    /* 2x2 little-endian colour PFM. */
    static const char pfm_head[] = "PF\n2 2\n-1\n";
    unsigned char pfm[sizeof pfm_head - 1 + 2 * 2 * 3 * 4];
    memcpy(pfm, pfm_head, sizeof pfm_head - 1);
    for (int k = 0; k < 12; ++k) {
        float v = (k / 3) % 3 == 0 ? 0.9f : 0.1f;
        memcpy(pfm + sizeof pfm_head - 1 + 4 * k, &v, 4);
    }
    unsigned char bin[44] = {0};
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint16_t idx[3] = {0, 1, 2};
    memcpy(bin, pos, sizeof pos);
    memcpy(bin + 36, idx, sizeof idx);
    static const char tri_gltf[] =
        "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"buffers\":[{\"byteLength\":44,\"uri\":\"tri.bin\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
        "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
        "\"min\":[0,0,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5123,\"count\":3,"
        "\"type\":\"SCALAR\"}]}";
    char path[1024];
    fuzz_write("quad.obj", quad_obj, sizeof quad_obj - 1, path, sizeof path);
    fuzz_write("quad.mtl", quad_mtl, sizeof quad_mtl - 1, path, sizeof path);
    fuzz_write("checker.pfm", pfm, sizeof pfm, path, sizeof path);
    fuzz_write("tri.bin", bin, sizeof bin, path, sizeof path);
    fuzz_write("tri.gltf", tri_gltf, sizeof tri_gltf - 1, path, sizeof path);
}

/* With IC_FUZZ_VERBOSE set, a harness prints what the loader said (for checking that seeds load). */
static inline void fuzz_report(int ok, const char *message)
{
    static int verbose = -1;
    if (verbose < 0)
        verbose = getenv("IC_FUZZ_VERBOSE") != NULL;
    if (verbose)
        fprintf(stderr, "  -> %s\n", ok ? "loaded" : message);
}

#endif
