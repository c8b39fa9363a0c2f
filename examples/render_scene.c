/*
 * render_scene.c — the renderer as a library (irrcache/render.h, irrcache/image.h): load a scene, render
 * a small image with irradiance caching, write it.
 *
 *   render_scene SCENE.json OUT.png|.exr|.hdr|.pfm [SIZE]     SIZE: width and height, default 64
 */
#include <irrcache/image.h>
#include <irrcache/render.h>
#include <irrcache/version.h>

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: render_scene SCENE.json OUT.png [SIZE]\n");
        return 2;
    }
    ic_error err;
    ic_scene_load_options load = {0}; /* zero means default */
    load.width = load.height = argc > 3 ? atoi(argv[3]) : 64;
    ic_scene *scene = NULL;
    if (ic_scene_load(argv[1], &load, &scene, &err) != IC_OK) {
        fprintf(stderr, "render_scene: %s\n", err.message);
        return 1;
    }

    ic_render_options opt = {0}; /* zero means default, or the scene file's value */
    opt.integrator = IC_INTEGRATOR_IC;
    opt.spp = 16;
    ic_image img = {0};
    ic_render_stats stats;
    int status = 1;
    if (ic_render(scene, &opt, &img, &stats, &err) != IC_OK) {
        fprintf(stderr, "render_scene: %s\n", err.message);
    } else if (ic_image_write(argv[2], &img, NULL, &err) != IC_OK) {
        fprintf(stderr, "render_scene: %s\n", err.message);
    } else {
        printf("irrcache %s: %dx%d, %d spp, %u records, %.2f s -> %s\n", ic_version(), img.width, img.height,
               stats.spp, stats.records, stats.seconds, argv[2]);
        status = 0;
    }
    ic_image_free(&img);
    ic_scene_free(scene);
    return status;
}
