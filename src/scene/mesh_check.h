/*
 * mesh_check.h — structure checks of mesh files, made before assimp imports them (mesh_import.c).
 *
 * assimp 5.2 (Debian 12) trusts what a file declares: faces that name vertices past the end crash its
 * post-processing, a PLY header without end_header makes it loop or read past its buffer, and an
 * exception thrown half-way through an import (a word where a number belongs, an index out of range,
 * bad base64) leaks what it had built. Each check here reads the file as the format defines it and
 * refuses such input with a one-line error naming the file (and line or element) and what to do, so
 * that assimp only ever sees files it handles. Each returns IC_OK for a file it has nothing against;
 * fp is read from its start and left at an unspecified position.
 */
#ifndef IC_SCENE_MESH_CHECK_H
#define IC_SCENE_MESH_CHECK_H

#include "irrcache/common.h"
#include "irrcache/render.h" /* ic_scene */

#include <stddef.h>
#include <stdio.h>

/* PLY (mesh_check_ply.c): the header's grammar, every element count against max_elements, then the whole
 * body, ascii or binary: the values each property needs, present and numbers, vertex coordinates, normals and
 * texture coordinates finite, face index lists of sane length naming existing vertices. */
ic_result ic_ply_check(FILE *fp, const char *path, unsigned long long max_elements, ic_error *err);

/* OBJ (mesh_check_obj.c): vertex coordinates, texture coordinates and normals finite, every index of a face,
 * line or point naming an existing vertex, and the vertices and the faces each at most max_elements (counted
 * before assimp reads the file). */
ic_result ic_obj_check(FILE *fp, const char *path, unsigned long long max_elements, ic_error *err);
/* An MTL file's Kd, Ks and Ke colours: negative or non-finite values are an error naming the MTL file, its
 * line and the material (mesh_check_obj.c). A file that cannot be opened is IC_OK (assimp warns). What the
 * import does not apply is warned into s (when not NULL), with the line: a texture map's options -s, -o, -t
 * other than their defaults and -clamp on (assimp drops the first three; irrcache repeats every texture). */
ic_result ic_mtl_check(const char *mtl_path, ic_scene *s, ic_error *err);
/* 1 if v is negative or not a number: no meaning as an albedo or a radiance. */
int ic_bad_color_component(float v);

/* glTF (mesh_check_gltf.c), what assimp's glTF 2 importer must accept lest assimp offer the file to every
 * other importer: ic_glb_check for a .glb (magic "glTF", version 2, the JSON and BIN chunks' lengths against
 * the bytes fp holds), ic_gltf_check for a .gltf (text, not binary); then for both, strictly valid JSON
 * with "asset": {"version": "2…"}, each buffer's and image's data URI valid base64 (of the buffer's
 * byteLength), each buffer file as long as its byteLength. */
ic_result ic_glb_check(FILE *fp, const char *path, ic_error *err);
ic_result ic_gltf_check(FILE *fp, const char *path, ic_error *err);
/* The JSON text of a glTF file (.gltf: the file; .glb: its JSON chunk), malloc'd and NUL-terminated, at most
 * 1 GiB; NULL if there is none or it cannot be read. *len gets its length. */
char *ic_gltf_json(FILE *fp, size_t *len);

#endif
