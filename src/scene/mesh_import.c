/*
 * mesh_import.c — mesh files (OBJ+MTL, glTF 2.0 / .glb, PLY, anything assimp reads) into the scene.
 *
 * assimp pre-transforms the node hierarchy (merging the meshes of one material and vertex format, each
 * placed once per node that holds it) and joins identical vertices, so each file arrives as flat meshes in
 * file space; we apply the scene's transform, triangulate polygons (ic_tess_polygon: assimp 5.2's own step
 * gets concave ones wrong) and append to the world-space triangle soup.
 * PreTransformVertices keeps the winding of a mesh under a mirroring node (a negative determinant, e.g. a
 * glTF node scaled by -1 on one axis), which would turn it inside out: we swap the winding of those
 * placements in the merged meshes before the other steps run (collect_instances, flip_mirrored). Normals
 * are not generated: a mesh without them is shaded flat (a zero normal at a vertex means "use the
 * geometric normal", see scene_query.c). Zero-area triangles are dropped and counted: Embree would never
 * hit them and they have no normal.
 *
 * Materials map to the renderer's four types (docs/scene-format.md, "Materials from mesh files"):
 * - OBJ/MTL (and other Phong-style formats): illum 4/6/7, or d < 1 with Ni > 1, is glass (ior Ni);
 *   illum 3/5 with Ks > 0 and Ns >= 10000 is a mirror tinted Ks; Ks > 0 and Ns > 0 is glossy
 *   (Lambert Kd + normalized modified Phong Ks, exponent Ns); otherwise diffuse. Ke is emission.
 * - glTF: base colour (factor × texture), metallic m and roughness r on the GGX models (α = r²):
 *   m = 1 a rough conductor, else a rough plastic blended with the conductor by m (convert_gltf);
 *   KHR_materials_transmission > 0 is glass;
 *   emission = emissiveFactor × KHR_materials_emissive_strength; doubleSided emits both ways.
 *   (assimp 5.2 drops KHR_materials_emissive_strength, so we read it from the file's JSON ourselves.)
 *
 * A gzip-compressed mesh (NAME.EXT.gz, RFC 1952, concatenated members allowed) is inflated into memory
 * with zlib and handed to assimp through its file-system callbacks under the name NAME.EXT, which picks
 * the format, and in NAME.EXT's folder, so that the MTL files and buffers it names are found where the
 * compressed file lies; messages name the .gz file.
 *
 * Every import, compressed or not, goes through those callbacks, so that each file assimp opens (the
 * mesh, MTL files, glTF buffers, and the names it probes) is checked to lie in the folders the scene may
 * read from (ic_scene_path_allowed; docs/scene-format.md, "Paths"); the MTL files we read ourselves and
 * the textures are checked the same way.
 *
 * Before assimp sees a file, its structure is checked (mesh_check.h: mesh_check_ply.c, mesh_check_obj.c,
 * mesh_check_gltf.c): assimp 5.2 crashes, hangs or leaks on some malformed files, and those checks
 * refuse them with a message naming the file and the line or element.
 */
#include "scene/scene_internal.h"
#include "core/read_file.h"

#include "scene/mesh_check.h"
#include "scene/tessellate.h"

#include "core/vecmath.h"

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/version.h>
#include <cjson/cJSON.h>
#include <zlib.h>

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Phong exponents at or above this are treated as ideal mirrors (illum 3/5, glTF metals). */
#define MIRROR_EXPONENT 10000.0f
/* Largest mesh a .gz file may inflate to (a guard against a corrupt or hostile length). */
#define GZIP_MAX_BYTES ((size_t)1 << 31)

/* The mesh file as the importer reads it: the file itself, or a gzip-compressed file inflated into memory. */
typedef struct mesh_source {
    const char *path;             /* the file the scene names: messages name it */
    char name[IC_SCENE_PATH_MAX]; /* path, or path without ".gz": its extension is the format */
    char *data;                   /* the inflated bytes; NULL: read path itself */
    size_t size;
} mesh_source;

/* Inflates the gzip file at path into *out (malloc'd, *size bytes). */
static ic_result gunzip_file(const char *path, char **out, size_t *size, ic_error *err)
{
    *out = NULL;
    *size = 0;
    FILE *fp;
    ic_result opened = ic_open_regular_file(path, "compressed mesh", &fp, err);
    if (opened != IC_OK)
        return opened;
    enum { CHUNK = 1 << 16 };
    z_stream z;
    memset(&z, 0, sizeof z);
    unsigned char *in = malloc(CHUNK);
    if (!in || inflateInit2(&z, 15 + 16) != Z_OK) { /* 15-bit window, gzip wrapper only */
        free(in);
        fclose(fp);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory to inflate it", path);
    }
    size_t cap = 0, len = 0, read_total = 0;
    char *buf = NULL;
    int ended = 0; /* a member ended and no input followed it yet */
    ic_result r = IC_OK;
    for (;;) {
        if (z.avail_in == 0) {
            size_t n = fread(in, 1, CHUNK, fp);
            if (n == 0) {
                if (ferror(fp))
                    r = ic_error_set(err, IC_ERR_IO, "%s: read error after %zu bytes; check the file", path, read_total);
                break;
            }
            read_total += n;
            z.next_in = in;
            z.avail_in = (uInt)n;
        }
        if (ended) { /* another member follows (gzip a b > c concatenates) */
            inflateReset(&z);
            ended = 0;
        }
        if (len == cap) {
            size_t grown = cap ? 2 * cap : (size_t)1 << 20;
            char *q = grown <= GZIP_MAX_BYTES ? realloc(buf, grown) : NULL;
            if (!q) {
                r = grown <= GZIP_MAX_BYTES
                        ? ic_error_set(err, IC_ERR_OOM, "%s: out of memory to inflate it", path)
                        : ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: inflates to more than %zu MiB; decompress it and "
                                       "load the file itself", path, GZIP_MAX_BYTES >> 20);
                break;
            }
            buf = q;
            cap = grown;
        }
        z.next_out = (Bytef *)buf + len;
        z.avail_out = (uInt)(cap - len < UINT_MAX ? cap - len : UINT_MAX);
        int zr = inflate(&z, Z_NO_FLUSH);
        len = (size_t)((char *)z.next_out - buf);
        if (zr == Z_STREAM_END) {
            ended = 1;
        } else if (zr != Z_OK && zr != Z_BUF_ERROR) { /* Z_BUF_ERROR: needs more input or room, given above */
            r = ic_error_set(err, IC_ERR_PARSE, "%s: corrupt or not gzip data (%s at compressed byte %zu); "
                             "compress the mesh again or load it uncompressed", path, z.msg ? z.msg : "invalid data",
                             read_total - z.avail_in);
            break;
        }
    }
    if (r == IC_OK && !ended && read_total == 0)
        r = ic_error_set(err, IC_ERR_PARSE, "%s: empty file, no gzip data; compress the mesh again", path);
    else if (r == IC_OK && !ended)
        r = ic_error_set(err, IC_ERR_PARSE, "%s: truncated gzip data (the stream stops after %zu bytes); compress "
                         "the mesh again or copy the whole file", path, read_total);
    inflateEnd(&z);
    free(in);
    fclose(fp);
    if (r != IC_OK) {
        free(buf);
        return r;
    }
    *out = buf;
    *size = len;
    return IC_OK;
}

/* Fills src for the mesh at path: a ".gz" file is inflated. */
static ic_result source_load(const char *path, mesh_source *src, ic_error *err)
{
    memset(src, 0, sizeof *src);
    src->path = path;
    snprintf(src->name, sizeof src->name, "%s", path);
    char ext[16];
    ic_path_extension(path, ext, sizeof ext);
    if (strcmp(ext, ".gz") != 0) {
        /* a FIFO would block the structure check's read for ever: only a regular file goes on */
        FILE *fp;
        ic_result r = ic_path_exists(path) ? ic_open_regular_file(path, "mesh file", &fp, err) : IC_OK;
        if (r == IC_OK && ic_path_exists(path))
            fclose(fp);
        return r;
    }
    src->name[strlen(src->name) - 3] = '\0';
    return gunzip_file(path, &src->data, &src->size, err);
}

/* The mesh's bytes as a stream (NULL if it cannot be read). */
static FILE *source_open(const mesh_source *src)
{
    if (!src->data)
        return fopen(src->path, "rb");
    return src->size ? fmemopen(src->data, src->size, "rb") : NULL;
}

/* assimp's file system for every mesh: an inflated mesh's name opens the bytes in memory; any other file
 * (the mesh itself, MTL files, glTF buffers) is opened from disk if it lies in the folders the scene may
 * read from (ic_scene_path_allowed), and otherwise refused and remembered, so that the import reports it
 * instead of assimp's "cannot open" (or, for an MTL file, nothing at all). */
typedef struct source_fs {
    const mesh_source *src;
    const ic_scene_builder *b;
    char refused[IC_SCENE_PATH_MAX]; /* the first name refused ("": none) */
} source_fs;

typedef struct source_file {
    struct aiFile file; /* first: assimp hands back a pointer to it */
    FILE *fp;           /* a file on disk, or NULL: the inflated mesh */
    const mesh_source *src;
    size_t pos;
} source_file;

static size_t source_read(struct aiFile *f, char *buf, size_t size, size_t count)
{
    source_file *sf = (source_file *)f;
    if (sf->fp)
        return fread(buf, size, count, sf->fp);
    if (size == 0)
        return 0;
    size_t n = (sf->src->size - sf->pos) / size;
    if (n > count)
        n = count;
    memcpy(buf, sf->src->data + sf->pos, n * size);
    sf->pos += n * size;
    return n;
}

static size_t source_write(struct aiFile *f, const char *buf, size_t size, size_t count)
{
    (void)f;
    (void)buf;
    (void)size;
    (void)count;
    return 0; /* the importer only reads */
}

static size_t source_tell(struct aiFile *f)
{
    source_file *sf = (source_file *)f;
    if (!sf->fp)
        return sf->pos;
    long at = ftell(sf->fp);
    return at < 0 ? 0 : (size_t)at;
}

static size_t source_size(struct aiFile *f)
{
    source_file *sf = (source_file *)f;
    if (!sf->fp)
        return sf->src->size;
    long at = ftell(sf->fp), end = -1;
    if (at >= 0 && fseek(sf->fp, 0, SEEK_END) == 0) {
        end = ftell(sf->fp);
        fseek(sf->fp, at, SEEK_SET);
    }
    return end < 0 ? 0 : (size_t)end;
}

static enum aiReturn source_seek(struct aiFile *f, size_t offset, enum aiOrigin origin)
{
    source_file *sf = (source_file *)f;
    if (sf->fp) {
        int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
        return offset <= LONG_MAX && fseek(sf->fp, (long)offset, whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
    }
    size_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? sf->pos : sf->src->size;
    if (offset > sf->src->size - base)
        return aiReturn_FAILURE;
    sf->pos = base + offset;
    return aiReturn_SUCCESS;
}

static void source_flush(struct aiFile *f)
{
    (void)f;
}

static struct aiFile *source_fs_open(struct aiFileIO *io, const char *name, const char *mode)
{
    source_fs *fs = (source_fs *)(void *)io->UserData;
    const mesh_source *src = fs->src;
    FILE *fp = NULL;
    if (!src->data || strcmp(name, src->name) != 0) {
        char real[IC_SCENE_PATH_MAX];
        if (!ic_scene_path_allowed(fs->b, name, real, sizeof real)) {
            if (real[0] && !fs->refused[0]) /* a file that is there, outside; a missing one is just missing */
                snprintf(fs->refused, sizeof fs->refused, "%s", name);
            return NULL;
        }
        if ((fp = fopen(name, mode)) == NULL)
            return NULL;
        /* Only regular files: a directory (an MTL named ".") opens, then reports an absurd size, and assimp
         * leaks the stream when the reserve for it throws (found by the mesh_obj fuzz target). */
        struct stat st;
        if (fstat(fileno(fp), &st) != 0 || !S_ISREG(st.st_mode)) {
            fclose(fp);
            return NULL;
        }
    }
    source_file *sf = calloc(1, sizeof *sf);
    if (!sf) {
        if (fp)
            fclose(fp);
        return NULL;
    }
    sf->fp = fp;
    sf->src = src;
    sf->file.ReadProc = source_read;
    sf->file.WriteProc = source_write;
    sf->file.TellProc = source_tell;
    sf->file.FileSizeProc = source_size;
    sf->file.SeekProc = source_seek;
    sf->file.FlushProc = source_flush;
    return &sf->file;
}

static void source_fs_close(struct aiFileIO *io, struct aiFile *f)
{
    (void)io;
    source_file *sf = (source_file *)f;
    if (sf && sf->fp)
        fclose(sf->fp);
    free(sf);
}

static const struct aiScene *source_import(mesh_source *src, source_fs *fs, unsigned flags)
{
    struct aiFileIO io = {source_fs_open, source_fs_close, (aiUserData)(void *)fs};
    return aiImportFileEx(src->name, flags, &io);
}

/* Where a file a mesh names is reported: the scene file's line of the mesh's path, or the bare mesh. */
static const char *import_where(const ic_scene_builder *b, const char *mesh_path)
{
    return b->import_where ? b->import_where : mesh_path;
}

/* The error for a file the mesh at mesh_path names (`kind`: "MTL file", ...) that lies outside the
 * folders the scene may read from. */
static ic_result check_named_file(const ic_scene_builder *b, const char *mesh_path, const char *kind,
                                  const char *path, ic_error *err)
{
    char desc[2 * IC_SCENE_PATH_MAX + 64];
    snprintf(desc, sizeof desc, "%s '%s' named by mesh '%s'", kind, path, mesh_path);
    return ic_scene_check_path(b, path, import_where(b, mesh_path), desc, err);
}

/* Runs a structure check of mesh_check.h on the mesh's bytes (IC_OK if they cannot be opened: the importer
 * reports that). */
static ic_result run_check(const mesh_source *src, ic_result (*check)(FILE *, const char *, ic_error *), ic_error *err)
{
    FILE *fp = source_open(src);
    if (!fp)
        return IC_OK;
    ic_result r = check(fp, src->path, err);
    fclose(fp);
    return r;
}

/* run_check for the checks that also count elements against max_elements (PLY, OBJ). */
static ic_result run_check_max(const mesh_source *src,
                               ic_result (*check)(FILE *, const char *, unsigned long long, ic_error *),
                               unsigned long long max_elements, ic_error *err)
{
    FILE *fp = source_open(src);
    if (!fp)
        return IC_OK;
    ic_result r = check(fp, src->path, max_elements, err);
    fclose(fp);
    return r;
}

/* OBJ files: assimp reads the MTL files and keeps no line numbers, so check the colours of every file the
 * OBJ's `mtllib` lines name (relative to the OBJ's folder) ourselves, and first that each lies in the
 * folders the scene may read from. */
static ic_result check_obj_materials(const ic_scene_builder *b, const mesh_source *src, const char *obj_dir,
                                     ic_error *err)
{
    FILE *fp = source_open(src);
    if (!fp)
        return IC_OK;
    char line[4096];
    ic_result r = IC_OK;
    while (r == IC_OK && fgets(line, sizeof line, fp)) {
        const char *c = line;
        while (*c == ' ' || *c == '\t')
            ++c;
        if (strncmp(c, "mtllib", 6) || (c[6] != ' ' && c[6] != '\t'))
            continue;
        char names[4096];
        snprintf(names, sizeof names, "%s", c + 7);
        names[strcspn(names, "\r\n")] = '\0';
        char *save = NULL;
        for (char *name = strtok_r(names, " \t", &save); name && r == IC_OK; name = strtok_r(NULL, " \t", &save)) {
            char mtl[IC_SCENE_PATH_MAX];
            if (!ic_path_join(obj_dir, name, mtl, sizeof mtl))
                continue;
            if (access(mtl, F_OK) == 0) /* a missing one is assimp's warning; one outside is refused */
                r = check_named_file(b, src->path, "MTL file", mtl, err);
            if (r == IC_OK)
                r = ic_mtl_check(mtl, b->scene, err);
        }
    }
    fclose(fp);
    return r;
}

/* Any format: the colours as assimp hands them over, for files whose lines we do not read ourselves. */
static ic_result check_material_colors(const struct aiMaterial *am, const char *mesh_path, const char *name,
                                       ic_error *err)
{
    static const char *const keys[4] = {"$clr.diffuse", "$clr.specular", "$clr.emissive", "$clr.base"};
    static const char *const what[4] = {"diffuse colour", "specular colour", "emission", "base colour"};
    for (int k = 0; k < 4; ++k) {
        struct aiColor4D c;
        if (aiGetMaterialColor(am, keys[k], 0, 0, &c) != aiReturn_SUCCESS)
            continue;
        if (ic_bad_color_component(c.r) || ic_bad_color_component(c.g) || ic_bad_color_component(c.b))
            return ic_error_set(err, IC_ERR_PARSE,
                                "%s: material '%s': %s (%g %g %g) has a negative or non-finite value; give values "
                                ">= 0",
                                mesh_path, name, what[k], (double)c.r, (double)c.g, (double)c.b);
    }
    return IC_OK;
}

static ic_vec3 color_or(const struct aiMaterial *am, const char *key, ic_vec3 fallback)
{
    struct aiColor4D c;
    if (aiGetMaterialColor(am, key, 0, 0, &c) == aiReturn_SUCCESS)
        return v3(c.r, c.g, c.b);
    return fallback;
}

static float float_or(const struct aiMaterial *am, const char *key, float fallback)
{
    ai_real f;
    unsigned int n = 1;
    if (aiGetMaterialFloatArray(am, key, 0, 0, &f, &n) == aiReturn_SUCCESS && n == 1)
        return (float)f;
    return fallback;
}

static int int_or(const struct aiMaterial *am, const char *key, int fallback)
{
    int v;
    unsigned int n = 1;
    if (aiGetMaterialIntegerArray(am, key, 0, 0, &v, &n) == aiReturn_SUCCESS && n == 1)
        return v;
    return fallback;
}

/* First texture of type t, or 0. */
static int texture_path(const struct aiMaterial *am, enum aiTextureType t, char *out, size_t size)
{
    struct aiString s;
    if (aiGetMaterialTextureCount(am, t) == 0)
        return 0;
    if (aiGetMaterialTexture(am, t, 0, &s, NULL, NULL, NULL, NULL, NULL, NULL) != aiReturn_SUCCESS)
        return 0;
    if (s.length == 0)
        return 0;
    snprintf(out, size, "%s", s.data);
    return 1;
}

static ic_vec3 clamp_color(ic_vec3 c)
{
    return v3(ic_clampf(isfinite(c.x) ? c.x : 0.0f, 0.0f, INFINITY), ic_clampf(isfinite(c.y) ? c.y : 0.0f, 0.0f, INFINITY),
              ic_clampf(isfinite(c.z) ? c.z : 0.0f, 0.0f, INFINITY));
}

static void convert_phong(const struct aiMaterial *am, ic_material *m)
{
    m->kd = color_or(am, "$clr.diffuse", v3s(0.6f));
    m->ks = color_or(am, "$clr.specular", v3s(0.0f));
    m->ns = float_or(am, "$mat.shininess", 0.0f);
    m->emission = color_or(am, "$clr.emissive", v3s(0.0f));
    int illum = int_or(am, "$mat.illum", 2);
    float d = float_or(am, "$mat.opacity", 1.0f);
    float ni = float_or(am, "$mat.refracti", 1.0f);
    int has_ks = v3_maxc(m->ks) > 0.0f;
    if (illum == 4 || illum == 6 || illum == 7 || (d < 1.0f && ni > 1.0f)) {
        m->type = IC_MAT_GLASS;
        m->ior = ni > 1.0f ? ni : 1.5f;
        if (!has_ks)
            m->ks = v3s(1.0f);
    } else if ((illum == 3 || illum == 5) && has_ks && m->ns >= MIRROR_EXPONENT) {
        m->type = IC_MAT_MIRROR;
    } else if (has_ks && m->ns > 0.0f) {
        m->type = IC_MAT_GLOSSY;
        m->ns = ic_clampf(m->ns, 1.0f, MIRROR_EXPONENT);
    } else {
        m->type = IC_MAT_DIFFUSE;
    }
}

/* KHR_materials_emissive_strength of each assimp material of a glTF file (1 where absent), read from the
 * file's JSON (.gltf text, or the JSON chunk of a .glb): assimp 5.2 does not pass it on. assimp numbers
 * the materials in the order the meshes first use them and leaves out unused ones, so assimp material i
 * is not glTF material i (a file whose meshes used material 1 first swapped two lamps' strengths): each
 * is matched to the glTF material of the same name, or where names do not decide, of the same emissive
 * and base colour, metallic and roughness factors. A tie between materials of different strengths keeps
 * the one at the same index, else the first. Returns NULL if the file cannot be read. */
typedef struct gltf_mat_key {
    char name[128];
    float emissive[3], base[3], metallic, roughness, strength;
} gltf_mat_key;

static void json_floats(const cJSON *arr, float *out, int n)
{
    for (int k = 0; k < n && cJSON_IsArray(arr); ++k) {
        const cJSON *v = cJSON_GetArrayItem(arr, k);
        if (cJSON_IsNumber(v))
            out[k] = (float)v->valuedouble;
    }
}

static int same_floats(const float *a, const float *b, int n)
{
    for (int k = 0; k < n; ++k)
        if (!(fabsf(a[k] - b[k]) <= 1e-5f * (1.0f + fabsf(b[k]))))
            return 0;
    return 1;
}

static float *gltf_emissive_strengths(const mesh_source *src, const struct aiScene *ai)
{
    FILE *fp = source_open(src);
    if (!fp)
        return NULL;
    size_t len = 0;
    char *text = ic_gltf_json(fp, &len);
    fclose(fp);
    const unsigned count = ai->mNumMaterials;
    float *out = NULL;
    cJSON *root = text ? cJSON_ParseWithLength(text, len) : NULL;
    free(text);
    const cJSON *mats = root ? cJSON_GetObjectItemCaseSensitive(root, "materials") : NULL;
    int nj = cJSON_IsArray(mats) ? cJSON_GetArraySize(mats) : 0;
    gltf_mat_key *keys = calloc(nj > 0 ? (size_t)nj : 1, sizeof *keys);
    if (root && keys && (out = malloc(sizeof *out * (count ? count : 1))) != NULL) {
        for (int j = 0; j < nj; ++j) {
            const cJSON *m = cJSON_GetArrayItem(mats, j), *name = cJSON_GetObjectItemCaseSensitive(m, "name");
            gltf_mat_key *k = &keys[j];
            if (cJSON_IsString(name))
                snprintf(k->name, sizeof k->name, "%s", name->valuestring);
            const cJSON *pbr = cJSON_GetObjectItemCaseSensitive(m, "pbrMetallicRoughness");
            k->base[0] = k->base[1] = k->base[2] = 1.0f;
            k->metallic = k->roughness = 1.0f;
            json_floats(cJSON_GetObjectItemCaseSensitive(pbr, "baseColorFactor"), k->base, 3);
            const cJSON *mf = cJSON_GetObjectItemCaseSensitive(pbr, "metallicFactor");
            const cJSON *rf = cJSON_GetObjectItemCaseSensitive(pbr, "roughnessFactor");
            if (cJSON_IsNumber(mf))
                k->metallic = (float)mf->valuedouble;
            if (cJSON_IsNumber(rf))
                k->roughness = (float)rf->valuedouble;
            json_floats(cJSON_GetObjectItemCaseSensitive(m, "emissiveFactor"), k->emissive, 3);
            const cJSON *ext = cJSON_GetObjectItemCaseSensitive(m, "extensions");
            const cJSON *es = ext ? cJSON_GetObjectItemCaseSensitive(ext, "KHR_materials_emissive_strength") : NULL;
            const cJSON *v = es ? cJSON_GetObjectItemCaseSensitive(es, "emissiveStrength") : NULL;
            k->strength = cJSON_IsNumber(v) && v->valuedouble >= 0.0 && isfinite(v->valuedouble) ? (float)v->valuedouble
                                                                                                : 1.0f;
        }
        for (unsigned i = 0; i < count; ++i) {
            const struct aiMaterial *am = ai->mMaterials[i];
            struct aiString an;
            const char *name = aiGetMaterialString(am, "?mat.name", 0, 0, &an) == aiReturn_SUCCESS ? an.data : "";
            ic_vec3 e = color_or(am, "$clr.emissive", v3s(0.0f)), bc = color_or(am, "$clr.base", v3s(1.0f));
            const float emissive[3] = {e.x, e.y, e.z}, base[3] = {bc.x, bc.y, bc.z};
            const float metallic = float_or(am, "$mat.metallicFactor", 1.0f), rough = float_or(am, "$mat.roughnessFactor", 1.0f);
            int best = -1, same_index = 0, differ = 0;
            for (int pass = 0; pass < 2 && best < 0; ++pass) /* by name, then by the factors alone */
                for (int j = 0; j < nj; ++j) {
                    const gltf_mat_key *k = &keys[j];
                    if (pass == 0 ? !name[0] || strcmp(name, k->name) : !same_floats(emissive, k->emissive, 3) ||
                                                                            !same_floats(base, k->base, 3) ||
                                                                            !same_floats(&metallic, &k->metallic, 1) ||
                                                                            !same_floats(&rough, &k->roughness, 1))
                        continue;
                    if (best >= 0 && keys[best].strength != k->strength)
                        differ = 1;
                    if (best < 0)
                        best = j;
                    same_index |= j == (int)i;
                }
            if (best >= 0 && differ && same_index)
                best = (int)i;
            out[i] = best >= 0 ? keys[best].strength : (int)i < nj ? keys[i].strength : 1.0f;
        }
    }
    free(keys);
    cJSON_Delete(root);
    return out;
}

/* glTF's metallic-roughness material on the microfacet models: a metal (metallic 1) is a rough
 * conductor with F0 = base colour, a dielectric (metallic 0) a rough plastic with base kd = base colour
 * under a coat of index ior (F0 = 0.04 at the default 1.5), and metallic m in between the plastic blended
 * with the conductor, (1 − m)·plastic + m·conductor; GGX α = roughness² (the glTF specification's
 * appendix B). */
static void convert_gltf(const struct aiMaterial *am, float file_strength, ic_material *m)
{
    ic_vec3 base = color_or(am, "$clr.base", color_or(am, "$clr.diffuse", v3s(1.0f)));
    float metal = ic_clampf(float_or(am, "$mat.metallicFactor", 1.0f), 0.0f, 1.0f);
    float rough = ic_clampf(float_or(am, "$mat.roughnessFactor", 1.0f), 0.0f, 1.0f);
    m->alpha = rough * rough;
    m->kd = clamp_color(base);
    /* a newer assimp passes the strength on; otherwise use what we read from the file */
    float strength = float_or(am, "$mat.emissiveIntensity", file_strength);
    m->emission = v3_scale(color_or(am, "$clr.emissive", v3s(0.0f)), strength);
    m->two_sided_emission = int_or(am, "$mat.twosided", 0) != 0;
    float transmission = float_or(am, "$mat.transmission.factor", 0.0f);
    float ior = float_or(am, "$mat.refracti", 1.5f);
    m->ior = ior >= 1.0f ? ior : 1.5f; /* KHR_materials_ior allows 1 (no refraction, no coat) */
    if (transmission > 0.0f) {
        m->type = m->alpha > 0.0f ? IC_MAT_ROUGH_GLASS : IC_MAT_GLASS;
        m->ks = v3s(1.0f);
    } else if (metal >= 1.0f) {
        m->type = IC_MAT_CONDUCTOR;
        m->ks = m->kd;
    } else {
        m->type = IC_MAT_PLASTIC;
        m->ks = v3s(1.0f);
        m->metallic = metal;
    }
}

/* The folder an OBJ's materials name their textures from: that of its first `mtllib` file (the MTL
 * format's rule), else the OBJ's own folder. */
static void obj_material_dir(const mesh_source *src, const char *obj_dir, char *out, size_t size)
{
    snprintf(out, size, "%s", obj_dir);
    FILE *fp = source_open(src);
    if (!fp)
        return;
    char line[4096];
    while (fgets(line, sizeof line, fp)) {
        const char *c = line;
        while (*c == ' ' || *c == '\t')
            ++c;
        if (strncmp(c, "mtllib", 6) || (c[6] != ' ' && c[6] != '\t'))
            continue;
        c += 6;
        while (*c == ' ' || *c == '\t')
            ++c;
        char name[IC_SCENE_PATH_MAX], mtl[IC_SCENE_PATH_MAX];
        snprintf(name, sizeof name, "%s", c);
        name[strcspn(name, "\r\n")] = 0;
        if (name[0] && ic_path_join(obj_dir, name, mtl, sizeof mtl))
            ic_path_dirname(mtl, out, size);
        break;
    }
    fclose(fp);
}

/* The embedded texture a material's texture path names: "*N" (the N-th), or one whose file name is the
 * path's (aiScene::GetEmbeddedTexture's rule; the C interface has no such call); NULL if none. */
static const struct aiTexture *find_embedded(const struct aiScene *ai, const char *rel)
{
    if (!ai || !ai->mTextures)
        return NULL;
    if (rel[0] == '*') {
        char *end;
        long i = strtol(rel + 1, &end, 10);
        return *end == '\0' && end != rel + 1 && i >= 0 && i < (long)ai->mNumTextures ? ai->mTextures[i] : NULL;
    }
    const char *base = strrchr(rel, '/') ? strrchr(rel, '/') + 1 : rel;
    for (unsigned i = 0; i < ai->mNumTextures; ++i) {
        const char *f = ai->mTextures[i]->mFilename.data, *fb = strrchr(f, '/') ? strrchr(f, '/') + 1 : f;
        if (f[0] && !strcmp(fb, base))
            return ai->mTextures[i];
    }
    return NULL;
}

/* A texture held in the mesh file (a .glb's images, a "*N" reference): decoded from memory (PNG or JPEG), or
 * taken as uncompressed texels; labelled "mesh#name" so that materials sharing it share one texture. */
static ic_result embedded_texture(ic_scene_builder *b, const struct aiScene *ai, const char *rel, const char *mesh_path,
                                  int is_data, const char *owner, int32_t *index, ic_error *err)
{
    const struct aiTexture *et = find_embedded(ai, rel);
    if (!et || !et->pcData)
        return ic_error_set(err, IC_ERR_PARSE, "%s: embedded texture '%s' is not in the file; fix the file", owner, rel);
    char label[sizeof b->scene->textures[0].path];
    snprintf(label, sizeof label, "%.900s#%.100s", mesh_path, rel);
    ic_scene *s = b->scene;
    for (uint32_t i = 0; i < s->texture_count; ++i)
        if (!strcmp(s->textures[i].path, label) && s->textures[i].is_data == is_data) {
            *index = (int32_t)i;
            return IC_OK;
        }
    ic_image img;
    ic_error ierr;
    size_t max_pixels = ic_scene_max_texture_pixels(b->opt);
    ic_result r;
    if (et->mHeight == 0) {
        r = ic_image_decode_memory(et->pcData, et->mWidth, label, max_pixels, IC_SCENE_RAISE_TEXTURE_LIMIT, &img, &ierr);
    } else if ((size_t)et->mWidth * et->mHeight > max_pixels) {
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: embedded texture '%s' has %ux%u pixels; %s", owner, rel,
                            et->mWidth, et->mHeight, IC_SCENE_RAISE_TEXTURE_LIMIT);
    } else if ((r = ic_image_create(&img, (int)et->mWidth, (int)et->mHeight)) == IC_OK) {
        /* uncompressed texels (B, G, R, A bytes), sRGB like every 8-bit texture */
        for (size_t i = 0; i < (size_t)et->mWidth * et->mHeight; ++i) {
            img.rgb[3 * i] = ic_srgb8_to_linear(et->pcData[i].r);
            img.rgb[3 * i + 1] = ic_srgb8_to_linear(et->pcData[i].g);
            img.rgb[3 * i + 2] = ic_srgb8_to_linear(et->pcData[i].b);
        }
    } else {
        snprintf(ierr.message, sizeof ierr.message, "out of memory for embedded texture '%.100s'", rel);
    }
    if (r != IC_OK)
        return ic_error_set(err, r, "%s: %s", owner, ierr.message);
    return ic_scene_texture_add_as(b, label, is_data, &img, owner, index, err);
}

/* The texture a material names by path rel (embedded, or a file from tex_dir, else mesh_dir), loaded as colours
 * or values (is_data) into *index. */
static ic_result material_texture(ic_scene_builder *b, const struct aiScene *ai, const char *rel, int is_data,
                                  const char *mesh_path, const char *mesh_dir, const char *tex_dir, const char *name,
                                  int32_t *index, ic_error *err)
{
    char full[IC_SCENE_PATH_MAX], alt[IC_SCENE_PATH_MAX], owner[IC_SCENE_PATH_MAX + 160];
    snprintf(owner, sizeof owner, "%s: material '%s'", mesh_path, name);
    if (rel[0] == '*' || find_embedded(ai, rel))
        return embedded_texture(b, ai, rel, mesh_path, is_data, owner, index, err);
    if (!ic_path_join(tex_dir, rel, full, sizeof full) || !ic_path_join(mesh_dir, rel, alt, sizeof alt))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: texture path too long; shorten it", owner);
    if (!ic_path_exists(full) && ic_path_exists(alt))
        snprintf(full, sizeof full, "%s", alt);
    if (ic_path_exists(full)) {
        char kind[200];
        snprintf(kind, sizeof kind, "texture of material '%s',", name);
        ic_result rc = check_named_file(b, mesh_path, kind, full, err);
        if (rc != IC_OK)
            return rc;
    }
    return ic_scene_texture_load_as(b, full, is_data, owner, index, err);
}

/* mesh_dir: the mesh's folder; tex_dir: where its materials' texture paths start (an OBJ's MTL folder),
 * tried first, then mesh_dir (exporters that write paths from the OBJ's folder). */
static ic_result convert_material(ic_scene_builder *b, const struct aiScene *ai, const struct aiMaterial *am,
                                  const float *gltf_strength,
                                  const char *mesh_path, const char *mesh_dir, const char *tex_dir, ic_material *m,
                                  ic_error *err)
{
    memset(m, 0, sizeof *m);
    struct aiString name;
    if (aiGetMaterialString(am, "?mat.name", 0, 0, &name) == aiReturn_SUCCESS)
        snprintf(m->name, sizeof m->name, "%.127s", name.data);
    m->kd_texture = -1;
    m->ior = 1.5f;
    ic_result r = check_material_colors(am, mesh_path, m->name, err);
    if (r != IC_OK)
        return r;
    if (gltf_strength)
        convert_gltf(am, *gltf_strength, m);
    else
        convert_phong(am, m);
    /* (an MTL file's Ke was checked with its line; a glTF emissiveFactor times its strength is checked here) */
    if (ic_radiance_too_large(m->emission))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: material '%s': its emission is " IC_RADIANCE_LIMIT_FMT "; "
                            IC_RADIANCE_LIMIT_FIX, mesh_path, m->name, IC_RADIANCE_LIMIT_ARGS(m->emission));
    m->kd = clamp_color(m->kd);
    m->ks = clamp_color(m->ks);
    m->emission = clamp_color(m->emission);

    ic_result rc = IC_OK;
    char rel[IC_SCENE_PATH_MAX];
    int32_t index = -1;
    if (texture_path(am, aiTextureType_BASE_COLOR, rel, sizeof rel) || texture_path(am, aiTextureType_DIFFUSE, rel, sizeof rel))
        rc = material_texture(b, ai, rel, 0, mesh_path, mesh_dir, tex_dir, m->name, &m->kd_texture, err);
    /* a tangent-space normal map (glTF's normalTexture with its scale, MTL's `norm`) */
    if (rc == IC_OK && texture_path(am, aiTextureType_NORMALS, rel, sizeof rel)) {
        rc = material_texture(b, ai, rel, 1, mesh_path, mesh_dir, tex_dir, m->name, &index, err);
        m->normal_texture = index + 1;
        m->normal_scale = 1.0f;
        ai_real f;
        unsigned n = 1;
        if (aiGetMaterialFloatArray(am, "$tex.scale", aiTextureType_NORMALS, 0, &f, &n) == aiReturn_SUCCESS && n == 1)
            m->normal_scale = (float)f;
    }
    if (rc != IC_OK || !gltf_strength)
        return rc;
    /* glTF's metallicRoughnessTexture (assimp 5.2 files it as UNKNOWN; later versions also as METALNESS):
     * roughness from its green channel, metallic from its blue one */
    if (texture_path(am, aiTextureType_UNKNOWN, rel, sizeof rel) || texture_path(am, aiTextureType_METALNESS, rel, sizeof rel)) {
        rc = material_texture(b, ai, rel, 1, mesh_path, mesh_dir, tex_dir, m->name, &index, err);
        if (rc != IC_OK)
            return rc;
        m->roughness_texture = m->metallic_texture = index + 1;
        m->metallic = ic_clampf(float_or(am, "$mat.metallicFactor", 1.0f), 0.0f, 1.0f);
        if (m->type == IC_MAT_CONDUCTOR) { /* metallic varies over the surface: the blend of the plastic */
            m->type = IC_MAT_PLASTIC;
            m->ks = v3s(1.0f);
        }
    }
    return rc;
}

/* What a material's textures ask for that the import does not apply: an emission texture (any format), and in a
 * glTF file a texture read through a second set of texture coordinates (texCoord), a sampler that clamps or
 * mirrors instead of repeating, or a KHR_texture_transform. A bit of UNREAD_* each. */
enum { UNREAD_EMISSION = 1, UNREAD_UV_SET = 2, UNREAD_WRAP = 4, UNREAD_TRANSFORM = 8, UNREAD_KINDS = 4 };

static unsigned unread_texture_features(const struct aiMaterial *am, int is_gltf)
{
    unsigned found = aiGetMaterialTextureCount(am, aiTextureType_EMISSIVE) > 0 ? UNREAD_EMISSION : 0;
    /* the textures convert_material reads: base colour, normal map, metallic-roughness */
    static const enum aiTextureType read[] = {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE, aiTextureType_NORMALS,
                                              aiTextureType_UNKNOWN, aiTextureType_METALNESS};
    for (size_t k = 0; is_gltf && k < sizeof read / sizeof read[0]; ++k) {
        if (aiGetMaterialTextureCount(am, read[k]) == 0)
            continue;
        int v;
        unsigned n = 1;
        if (aiGetMaterialIntegerArray(am, "$tex.uvwsrc", read[k], 0, &v, &n) == aiReturn_SUCCESS && n == 1 && v != 0)
            found |= UNREAD_UV_SET;
        for (int axis = 0; axis < 2; ++axis) {
            n = 1;
            if (aiGetMaterialIntegerArray(am, axis ? "$tex.mapmodev" : "$tex.mapmodeu", read[k], 0, &v, &n) ==
                    aiReturn_SUCCESS && n == 1 && v != aiTextureMapMode_Wrap)
                found |= UNREAD_WRAP;
        }
        ai_real t[5]; /* aiUVTransform: translation, scaling, rotation */
        n = 5;
        if (aiGetMaterialFloatArray(am, "$tex.uvtrafo", read[k], 0, t, &n) == aiReturn_SUCCESS && n == 5 &&
            (t[0] != 0.0f || t[1] != 0.0f || t[2] != 1.0f || t[3] != 1.0f || t[4] != 0.0f))
            found |= UNREAD_TRANSFORM;
    }
    return found;
}

/* One warning per kind of unread texture feature of a mesh file, naming the first material that has it. */
static void warn_unread_texture_features(ic_scene *s, const char *mesh_path, const char first[UNREAD_KINDS][128])
{
    static const char *const what[UNREAD_KINDS] = {
        "has an emission texture (emissiveTexture, map_Ke), which is not read: it emits its emission colour "
        "uniformly; split the emitter into materials of their own colours",
        "reads a texture through a second set of texture coordinates (texCoord 1 or more), which is not read: the "
        "first set (TEXCOORD_0) is used; export the texture on the first set",
        "has a sampler that clamps or mirrors its texture, which is not applied: textures repeat beyond [0, 1]; "
        "keep the texture coordinates within [0, 1]",
        "has a texture transform (KHR_texture_transform), which is not applied: the texture coordinates are used as "
        "the file gives them; bake the transform into them"};
    for (int k = 0; k < UNREAD_KINDS; ++k)
        if (first[k][0])
            ic_scene_warn(s, "%s: material '%s' (and any other of the file's alike) %s", mesh_path, first[k], what[k]);
}

static int grow(void **p, size_t elem, size_t count)
{
    void *q = realloc(*p, elem * (count ? count : 1));
    if (!q)
        return 0;
    *p = q;
    return 1;
}

/* Grows per-vertex arrays for `add` more vertices; allocates normals/uvs (zero-filled for vertices
 * that had none) the first time a mesh brings them. */
static int grow_vertices(ic_scene *s, uint32_t add, int want_normals, int want_uvs)
{
    size_t old = s->vertex_count, total = old + add;
    if (!grow((void **)&s->positions, sizeof *s->positions, total))
        return 0;
    if (s->tangents && !grow((void **)&s->tangents, sizeof *s->tangents * 4, total))
        return 0;
    if (s->tangents) /* vertices without one: from their triangle's texture coordinates */
        memset(s->tangents + 4 * old, 0, sizeof *s->tangents * 4 * add);
    if (want_normals || s->normals) {
        int fresh = s->normals == NULL;
        if (!grow((void **)&s->normals, sizeof *s->normals, total))
            return 0;
        if (fresh)
            memset(s->normals, 0, sizeof *s->normals * old);
    }
    if (want_uvs || s->uvs) {
        int fresh = s->uvs == NULL;
        if (!grow((void **)&s->uvs, sizeof *s->uvs * 2, total))
            return 0;
        if (fresh)
            memset(s->uvs, 0, sizeof *s->uvs * 2 * old);
    }
    return 1;
}

/* Inverse transpose of the upper 3x3 of a row-major 4x4 (for normals), up to a positive scale, and its
 * determinant. */
static float normal_matrix(const float m[16], float n[9])
{
    float a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    float det = ic_mat4_det3(m);
    /* cofactor matrix = det · inverse transpose; its scale does not matter as normals are renormalized, but
     * its sign does: a mirroring transform (det < 0) turned every normal and the tangents' handedness
     * around, so the cofactors are taken times the sign of det */
    n[0] = e * i - f * h;
    n[1] = -(d * i - f * g);
    n[2] = d * h - e * g;
    n[3] = -(b * i - c * h);
    n[4] = a * i - c * g;
    n[5] = -(a * h - b * g);
    n[6] = b * f - c * e;
    n[7] = -(a * f - c * d);
    n[8] = a * e - b * d;
    if (det < 0.0f)
        for (int k = 0; k < 9; ++k)
            n[k] = -n[k];
    return det;
}

static ic_vec3 xform_point(const float m[16], struct aiVector3D p)
{
    return v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
              m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}

static ic_vec3 xform_normal(const float n[9], struct aiVector3D v)
{
    ic_vec3 r = v3(n[0] * v.x + n[1] * v.y + n[2] * v.z, n[3] * v.x + n[4] * v.y + n[5] * v.z,
                   n[6] * v.x + n[7] * v.y + n[8] * v.z);
    float l = v3_len(r);
    return (l > 0.0f && isfinite(l)) ? v3_scale(r, 1.0f / l) : v3s(0.0f);
}

/* The tangent frame of a vertex through the transform (m4 for the tangent and bitangent, nm for the normal)
 * as ic_scene.tangents holds it: the unit tangent and the bitangent's sign; zero if there is none. */
static void xform_tangent(const float m4[16], const float nm[9], const struct aiMesh *mesh, unsigned v, float out[4])
{
    memset(out, 0, sizeof(float) * 4);
    if (!mesh->mTangents || !mesh->mBitangents || !mesh->mNormals)
        return;
    struct aiVector3D ta = mesh->mTangents[v], ba = mesh->mBitangents[v];
    ic_vec3 t = v3(m4[0] * ta.x + m4[1] * ta.y + m4[2] * ta.z, m4[4] * ta.x + m4[5] * ta.y + m4[6] * ta.z,
                   m4[8] * ta.x + m4[9] * ta.y + m4[10] * ta.z);
    ic_vec3 bt = v3(m4[0] * ba.x + m4[1] * ba.y + m4[2] * ba.z, m4[4] * ba.x + m4[5] * ba.y + m4[6] * ba.z,
                    m4[8] * ba.x + m4[9] * ba.y + m4[10] * ba.z);
    ic_vec3 n = xform_normal(nm, mesh->mNormals[v]);
    float len = v3_len(t);
    if (!(len > 0.0f) || !isfinite(len) || !isfinite(v3_len(bt)))
        return;
    out[0] = t.x / len;
    out[1] = t.y / len;
    out[2] = t.z / len;
    out[3] = v3_dot(v3_cross(n, t), bt) < 0.0f ? -1.0f : 1.0f;
}

/* One placement of a mesh in the file's node tree, and where assimp's PreTransformVertices puts it: that
 * step merges the placements of one material and vertex format into one mesh, each one's faces and vertices
 * after the previous one's, with its node's transform baked into its vertices but its winding kept. */
typedef struct mesh_instance {
    unsigned material;        /* the mesh's */
    unsigned vformat;         /* which vertex attributes the mesh has (vertex_format) */
    size_t order;             /* the placement's rank in the walk */
    int mirrored;             /* its node's transform composed with its ancestors' has a negative determinant */
    unsigned faces, vertices; /* the mesh's */
    unsigned first[3];        /* the mesh's first face: its index count, first and last index */
    unsigned merged;          /* the merged mesh it goes to (UINT_MAX: none) and where in it: */
    unsigned face_offset, vertex_offset;
} mesh_instance;

/* The attributes a mesh has, as one number, as PreTransformVertices tells vertex formats apart: normals,
 * tangents, each texture coordinate set (and whether it has three components) and each colour set, none
 * without vertices; the merged meshes are in the order of these numbers within a material. */
static unsigned vertex_format(const struct aiMesh *mesh)
{
    unsigned f = 1;
    if (mesh->mNumVertices == 0)
        return f;
    if (mesh->mNormals)
        f |= 0x2;
    if (mesh->mTangents && mesh->mBitangents)
        f |= 0x4;
    for (unsigned k = 0; k < AI_MAX_NUMBER_OF_TEXTURECOORDS && k < 8 && mesh->mTextureCoords[k]; ++k)
        f |= (0x100u << k) | (mesh->mNumUVComponents[k] == 3 ? 0x10000u << k : 0);
    for (unsigned k = 0; k < AI_MAX_NUMBER_OF_COLOR_SETS && k < 8 && mesh->mColors[k]; ++k)
        f |= 0x1000000u << k;
    return f;
}

/* Whether a node's own transform mirrors (a negative determinant). A placement mirrors when an odd number
 * of the transforms from the root to its node do: the determinant of a product is the product of theirs. */
static int node_mirrors(const struct aiMatrix4x4 *m)
{
    double det = m->a1 * ((double)m->b2 * m->c3 - (double)m->b3 * m->c2) -
                 m->a2 * ((double)m->b1 * m->c3 - (double)m->b3 * m->c1) +
                 m->a3 * ((double)m->b1 * m->c2 - (double)m->b2 * m->c1);
    return det < 0.0;
}

/* Grouped by material, then by vertex format, in the walk's order within a group: the order in which
 * PreTransformVertices merges the placements. */
static int by_material(const void *pa, const void *pb)
{
    const mesh_instance *a = pa, *b = pb;
    if (a->material != b->material)
        return a->material < b->material ? -1 : 1;
    if (a->vformat != b->vformat)
        return a->vformat < b->vformat ? -1 : 1;
    return a->order < b->order ? -1 : a->order > b->order;
}

/* Every placement of a mesh in the node tree, depth first (a node's meshes, then its children in order),
 * in the order PreTransformVertices merges them and with where it puts each; *merged: how many meshes it
 * makes (a group of a material the file has, with faces and vertices, makes one). *out is malloc'ed. The
 * walk keeps its own stack: a file may nest its nodes deeper than the C stack would allow. */
static ic_result collect_instances(const struct aiScene *ai, const char *mesh_path, mesh_instance **out,
                                   size_t *count, unsigned *merged, ic_error *err)
{
    typedef struct {
        const struct aiNode *node;
        int mirrored;
    } pending;
    pending *stack = NULL;
    mesh_instance *inst = NULL;
    size_t depth = 0, stack_cap = 0, n = 0, cap = 0;
    if (ai->mRootNode) {
        if (!grow((void **)&stack, sizeof *stack, stack_cap = 16))
            goto oom;
        stack[depth].node = ai->mRootNode;
        stack[depth++].mirrored = node_mirrors(&ai->mRootNode->mTransformation);
    }
    while (depth > 0) {
        pending top = stack[--depth];
        for (unsigned i = 0; i < top.node->mNumMeshes; ++i) {
            if (top.node->mMeshes[i] >= ai->mNumMeshes)
                continue;
            const struct aiMesh *mesh = ai->mMeshes[top.node->mMeshes[i]];
            if (n == cap && !grow((void **)&inst, sizeof *inst, cap = cap ? 2 * cap : 16))
                goto oom;
            mesh_instance *in = &inst[n];
            memset(in, 0, sizeof *in);
            in->material = mesh->mMaterialIndex;
            in->vformat = vertex_format(mesh);
            in->order = n++;
            in->mirrored = top.mirrored;
            in->faces = mesh->mNumFaces;
            in->vertices = mesh->mNumVertices;
            if (mesh->mNumFaces > 0 && (in->first[0] = mesh->mFaces[0].mNumIndices) > 0) {
                in->first[1] = mesh->mFaces[0].mIndices[0];
                in->first[2] = mesh->mFaces[0].mIndices[in->first[0] - 1];
            }
        }
        if (depth + top.node->mNumChildren > stack_cap) {
            stack_cap = 2 * (depth + top.node->mNumChildren);
            if (!grow((void **)&stack, sizeof *stack, stack_cap))
                goto oom;
        }
        /* pushed last child first, so that the first child is walked next */
        for (unsigned i = top.node->mNumChildren; i-- > 0;) {
            stack[depth].node = top.node->mChildren[i];
            stack[depth++].mirrored = top.mirrored ^ node_mirrors(&top.node->mChildren[i]->mTransformation);
        }
    }
    free(stack);
    if (n > 1)
        qsort(inst, n, sizeof *inst, by_material);
    *merged = 0;
    for (size_t k = 0, end; k < n; k = end) {
        unsigned faces = 0, vertices = 0;
        for (end = k; end < n && inst[end].material == inst[k].material && inst[end].vformat == inst[k].vformat;
             ++end) {
            inst[end].face_offset = faces;
            inst[end].vertex_offset = vertices;
            faces += inst[end].faces;
            vertices += inst[end].vertices;
        }
        int kept = inst[k].material < ai->mNumMaterials && faces > 0 && vertices > 0;
        for (size_t j = k; j < end; ++j)
            inst[j].merged = kept ? *merged : UINT_MAX;
        *merged += kept;
    }
    *out = inst;
    *count = n;
    return IC_OK;
oom:
    free(stack);
    free(inst);
    return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for its node hierarchy", mesh_path);
}

/* After PreTransformVertices (and before Triangulate): swaps the winding of each mirrored placement's faces
 * in the merged meshes (a polygon's corners after its first are reversed), so that the front of the placed
 * mesh is the mirror image of the file's front, not its back. A merged mesh laid out otherwise than
 * collect_instances says (another assimp) is an error rather than a mesh turned inside out. */
static ic_result flip_mirrored(const struct aiScene *ai, const mesh_instance *inst, size_t count, unsigned merged,
                               const char *mesh_path, ic_error *err)
{
    for (size_t k = 0; k < count; ++k) {
        const mesh_instance *in = &inst[k];
        if (!in->mirrored || in->merged == UINT_MAX || in->faces == 0)
            continue;
        const struct aiMesh *mesh = ai->mNumMeshes == merged ? ai->mMeshes[in->merged] : NULL;
        /* the merged mesh's faces are assimp's to change: the step that made them has handed them over */
        const struct aiFace *f = mesh && mesh->mMaterialIndex == in->material &&
                                         (size_t)in->face_offset + in->faces <= mesh->mNumFaces
                                     ? mesh->mFaces + in->face_offset
                                     : NULL;
        if (!f || f->mNumIndices != in->first[0] ||
            (in->first[0] > 0 && (f->mIndices[0] != in->first[1] + in->vertex_offset ||
                                  f->mIndices[in->first[0] - 1] != in->first[2] + in->vertex_offset)))
            return ic_error_set(err, IC_ERR_UNSUPPORTED,
                                "%s: assimp %u.%u merged its meshes otherwise than expected, so its mirroring nodes "
                                "cannot keep their front side; apply the mirroring to the vertices in the file",
                                mesh_path, aiGetVersionMajor(), aiGetVersionMinor());
        for (unsigned j = 0; j < in->faces; ++j, ++f)
            for (unsigned a = 1, z = f->mNumIndices ? f->mNumIndices - 1 : 0; a < z; ++a, --z) {
                unsigned t = f->mIndices[a];
                f->mIndices[a] = f->mIndices[z];
                f->mIndices[z] = t;
            }
    }
    return IC_OK;
}

/* assimp's tangent step takes a polygon's tangent from its first three corners: a polygon whose first three
 * lie on a line (a corner on an edge, a corner repeated) has its corners rotated, in place, to start with the
 * corner of the largest area, so that the tangent comes from a triangle of the polygon's plane. */
static void lead_with_corner(const struct aiScene *ai)
{
    for (unsigned i = 0; i < ai->mNumMeshes; ++i) {
        const struct aiMesh *mesh = ai->mMeshes[i];
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const struct aiFace *face = &mesh->mFaces[f];
            unsigned n = face->mNumIndices, best = 0;
            float best_area = 0.0f;
            for (unsigned k = 0; n > 3 && k < n; ++k) {
                struct aiVector3D a = mesh->mVertices[face->mIndices[k]], b = mesh->mVertices[face->mIndices[(k + 1) % n]],
                                  c = mesh->mVertices[face->mIndices[(k + 2) % n]];
                float area = v3_len(v3_cross(v3(b.x - a.x, b.y - a.y, b.z - a.z), v3(c.x - a.x, c.y - a.y, c.z - a.z)));
                if (k == 0 && area > 0.0f)
                    break; /* the first corner will do: leave the polygon as the file gives it */
                if (area > best_area) {
                    best_area = area;
                    best = k;
                }
            }
            for (unsigned turn = 0; turn < best; ++turn) { /* rotate left by best: small polygons, rare */
                unsigned first = face->mIndices[0];
                memmove(face->mIndices, face->mIndices + 1, sizeof *face->mIndices * (n - 1));
                face->mIndices[n - 1] = first;
            }
        }
    }
}

static int finite3(struct aiVector3D a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

/* Every vertex's position, normal, first texture coordinates, tangent and bitangent finite, on the meshes as
 * the file gives them: a NaN normal would give NaN shading samples (black pixels once the film drops them), a
 * NaN texture coordinate a texture look-up nowhere, and a NaN tangent would be taken for none (xform_tangent)
 * and replaced by the triangle's own without a word. (A glTF TANGENT's w reaches here as the bitangent assimp
 * makes of it, the normal × the tangent times w. assimp's CalcTangentSpace runs later and only where the file
 * gives none; its NaN ones, for degenerate texture coordinates, are rightly taken for none.) Checked before assimp's steps, so that the message names the file's
 * mesh (a glTF primitive: "name-1" for a mesh's second one) and its vertex as the file numbers them (from 1):
 * PreTransformVertices merges the meshes of one material into one, JoinIdenticalVertices drops the vertices
 * no face uses and renumbers the others, and PreTransformVertices also gives NaN normals to the placements
 * of a node with a singular transform (a scale of 0, which hides a mesh), which are not the file's fault.
 * (An OBJ's or PLY's values were checked with their lines, mesh_check.h; the glTF file's accessors reach
 * here unchecked.) */
static ic_result check_finite_vertices(const struct aiScene *ai, const char *mesh_path, ic_error *err)
{
    for (unsigned i = 0; i < ai->mNumMeshes; ++i) {
        const struct aiMesh *mesh = ai->mMeshes[i];
        const struct aiVector3D *uv = mesh->mTextureCoords[0];
        for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
            const char *bad = !finite3(mesh->mVertices[v]) ? "coordinate"
                              : mesh->mNormals && !finite3(mesh->mNormals[v]) ? "normal"
                              : uv && !(isfinite(uv[v].x) && isfinite(uv[v].y)) ? "texture coordinate"
                              : mesh->mTangents && !finite3(mesh->mTangents[v]) ? "tangent"
                              : mesh->mBitangents && !finite3(mesh->mBitangents[v])
                                  ? "bitangent (made of the normal, the tangent and its w)"
                                  : NULL;
            if (bad)
                return ic_error_set(err, IC_ERR_PARSE,
                                    "%s: vertex %u of mesh '%s' has a non-finite %s; fix or remove it", mesh_path,
                                    v + 1, mesh->mName.data, bad);
        }
    }
    return IC_OK;
}

/* Whether triangle (p0, p1, p2) has no geometric normal, the test ic_scene_surface relies on: its cross
 * product is zero or not finite. Not its squared length, which overflows a float for edges beyond about
 * 4e9 (well inside IC_SCENE_MAX_COORD) and underflows below about 1e-10: such a triangle has a normal
 * (v3_norm_any) and an area (v3_len_any) and is kept. */
static int is_degenerate(ic_vec3 p0, ic_vec3 p1, ic_vec3 p2)
{
    ic_vec3 c = v3_cross(v3_sub(p1, p0), v3_sub(p2, p0));
    return v3_is_black(c) || !v3_is_finite(c);
}

/* Counts a zero-area triangle dropped from `where` (the scene warns once, naming the first place). */
static void drop_degenerate(ic_scene_builder *b, const char *where)
{
    if (b->scene->dropped_degenerate++ == 0)
        snprintf(b->dropped_where, sizeof b->dropped_where, "%s", where);
}

static ic_result append_meshes(ic_scene_builder *b, const struct aiScene *ai, const char *mesh_path,
                               const float m4[16], const char *xform_where, uint32_t material_base, int use_tangents,
                               ic_error *err)
{
    ic_scene *s = b->scene;
    size_t add_vertices = 0, add_faces = 0; /* faces: the triangles the polygons make, and points and lines */
    unsigned max_corners = 0;
    int any_normals = 0, any_uvs = 0, any_tangents = 0;
    for (unsigned i = 0; i < ai->mNumMeshes; ++i) {
        const struct aiMesh *mesh = ai->mMeshes[i];
        add_vertices += mesh->mNumVertices;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            unsigned n = mesh->mFaces[f].mNumIndices;
            add_faces += n > 3 ? n - 2 : 1;
            max_corners = n > max_corners ? n : max_corners;
        }
        any_normals |= mesh->mNormals != NULL;
        any_uvs |= mesh->mTextureCoords[0] != NULL;
        any_tangents |= use_tangents && mesh->mTangents != NULL;
    }
    if (any_tangents && !s->tangents) { /* the first mesh with tangents: the vertices before it have none */
        if (!(s->tangents = calloc(4 * ((size_t)s->vertex_count ? s->vertex_count : 1), sizeof *s->tangents)))
            return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for its geometry", mesh_path);
    }
    size_t max_elements = ic_scene_max_mesh_elements(b->opt);
    if (add_vertices > max_elements || add_faces > max_elements)
        return ic_error_set(err, IC_ERR_UNSUPPORTED,
                            "%s: %zu vertices and %zu faces, more than the limit of %zu; raise it with "
                            "--max-mesh-elements (max_mesh_elements of ic_scene_load_options) if the mesh is really "
                            "this large",
                            mesh_path, add_vertices, add_faces, max_elements);
    if (s->vertex_count + add_vertices > UINT32_MAX / 4 || s->triangle_count + add_faces > UINT32_MAX / 4)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: too many vertices or triangles; split the scene",
                            mesh_path);
    if (!grow_vertices(s, (uint32_t)add_vertices, any_normals, any_uvs) ||
        !grow((void **)&s->triangles, sizeof *s->triangles * 3, s->triangle_count + add_faces) ||
        !grow((void **)&s->triangle_material, sizeof *s->triangle_material, s->triangle_count + add_faces))
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for its geometry", mesh_path);

    /* a polygon's corners (positions and indices) and the triangles ic_tess_polygon makes of it */
    ic_vec3 *corner = NULL;
    uint32_t *scratch = NULL, *poly_tri = NULL;
    if (max_corners > 3 && (!(corner = malloc(sizeof *corner * max_corners)) ||
                            !(scratch = malloc(sizeof *scratch * max_corners)) ||
                            !(poly_tri = malloc(sizeof *poly_tri * 3 * (max_corners - 2))))) {
        free(corner);
        free(scratch);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for its polygons", mesh_path);
    }
    float nm[9];
    float det = normal_matrix(m4, nm);
    int flip = det < 0.0f; /* a mirroring transform reverses winding: swap to keep the front side */

    for (unsigned i = 0; i < ai->mNumMeshes; ++i) {
        const struct aiMesh *mesh = ai->mMeshes[i];
        uint32_t base = s->vertex_count;
        const struct aiVector3D *uv = mesh->mTextureCoords[0];
        for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
            struct aiVector3D p = mesh->mVertices[v];
            /* the file's values were checked (check_finite_vertices); a node's transform that overflows is not
             * caught there but by the test below, as NaN fails it */
            ic_vec3 q = xform_point(m4, p);
            if (!(fabsf(q.x) <= IC_SCENE_MAX_COORD && fabsf(q.y) <= IC_SCENE_MAX_COORD &&
                  fabsf(q.z) <= IC_SCENE_MAX_COORD)) {
                free(corner);
                free(scratch);
                free(poly_tri);
                if (xform_where)
                    return ic_error_set(err, IC_ERR_INVALID_ARG,
                                        "%s: the transform of '%s' takes its vertex %u (%g, %g, %g) to (%g, %g, %g), "
                                        "beyond the largest coordinate %g; give a smaller scale or translation",
                                        xform_where, mesh_path, v + 1, (double)p.x, (double)p.y, (double)p.z,
                                        (double)q.x, (double)q.y, (double)q.z, (double)IC_SCENE_MAX_COORD);
                return ic_error_set(err, IC_ERR_INVALID_ARG,
                                    "%s: vertex %u (%g, %g, %g) is beyond the largest coordinate %g; scale the mesh "
                                    "down",
                                    mesh_path, v + 1, (double)q.x, (double)q.y, (double)q.z,
                                    (double)IC_SCENE_MAX_COORD);
            }
            s->positions[base + v] = q;
            if (s->normals)
                s->normals[base + v] = mesh->mNormals ? xform_normal(nm, mesh->mNormals[v]) : v3s(0.0f);
            if (s->tangents && use_tangents)
                xform_tangent(m4, nm, mesh, v, s->tangents + 4 * ((size_t)base + v));
            if (s->uvs) {
                s->uvs[2 * (base + v) + 0] = uv && isfinite(uv[v].x) ? uv[v].x : 0.0f;
                s->uvs[2 * (base + v) + 1] = uv && isfinite(uv[v].y) ? uv[v].y : 0.0f;
            }
        }
        s->vertex_count += mesh->mNumVertices;
        uint32_t mat = material_base + mesh->mMaterialIndex;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const struct aiFace *face = &mesh->mFaces[f];
            unsigned n = face->mNumIndices;
            if (n < 3) { /* points and lines have no surface */
                ++b->material_dropped[mat];
                continue;
            }
            static const uint32_t one[3] = {0, 1, 2};
            const uint32_t *tri = one;
            uint32_t nt = 1;
            if (n > 3) { /* a polygon: triangles that keep its outline, concave or not */
                for (unsigned k = 0; k < n; ++k)
                    corner[k] = s->positions[base + face->mIndices[k]];
                ic_tess_polygon(corner, n, scratch, poly_tri, &nt);
                tri = poly_tri;
            }
            for (uint32_t j = 0; j < nt; ++j) {
                uint32_t i0 = base + face->mIndices[tri[3 * j]], i1 = base + face->mIndices[tri[3 * j + (flip ? 2 : 1)]],
                         i2 = base + face->mIndices[tri[3 * j + (flip ? 1 : 2)]];
                if (is_degenerate(s->positions[i0], s->positions[i1], s->positions[i2])) {
                    drop_degenerate(b, mesh_path);
                    ++b->material_dropped[mat];
                    continue;
                }
                uint32_t t = s->triangle_count++;
                s->triangles[3 * t + 0] = i0;
                s->triangles[3 * t + 1] = i1;
                s->triangles[3 * t + 2] = i2;
                s->triangle_material[t] = mat;
                ++b->material_tris[mat];
            }
        }
    }
    free(corner);
    free(scratch);
    free(poly_tri);
    return IC_OK;
}

ic_result ic_scene_add_material(ic_scene_builder *b, const ic_material *m, const char *source, uint32_t *index,
                                ic_error *err)
{
    ic_scene *s = b->scene;
    uint32_t n = s->material_count;
    char *path_copy = malloc(strlen(source) + 1);
    if (path_copy)
        memcpy(path_copy, source, strlen(source) + 1);
    if (!path_copy || !grow((void **)&b->mesh_paths, sizeof *b->mesh_paths, b->mesh_count + 1) ||
        !grow((void **)&s->materials, sizeof *s->materials, n + 1) ||
        !grow((void **)&b->material_dropped, sizeof *b->material_dropped, n + 1) ||
        !grow((void **)&b->material_tris, sizeof *b->material_tris, n + 1) ||
        !grow((void **)&b->material_mesh, sizeof *b->material_mesh, n + 1)) {
        free(path_copy);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for its materials", source);
    }
    b->mesh_paths[b->mesh_count++] = path_copy;
    s->materials[n] = *m;
    b->material_dropped[n] = b->material_tris[n] = 0;
    b->material_mesh[n] = b->mesh_count - 1;
    s->material_count = n + 1;
    *index = n;
    return IC_OK;
}

ic_result ic_scene_append_triangles(ic_scene_builder *b, const ic_vec3 *p, const ic_vec3 *n, uint32_t vertex_count,
                                    const uint32_t *tri, uint32_t tri_count, uint32_t material, const float xform[16],
                                    const char *where, ic_error *err)
{
    ic_scene *s = b->scene;
    if (s->vertex_count + (size_t)vertex_count > UINT32_MAX / 4 || s->triangle_count + (size_t)tri_count > UINT32_MAX / 4)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: too many vertices or triangles; split the scene", where);
    if (!grow_vertices(s, vertex_count, n != NULL, 0) ||
        !grow((void **)&s->triangles, sizeof *s->triangles * 3, s->triangle_count + tri_count) ||
        !grow((void **)&s->triangle_material, sizeof *s->triangle_material, s->triangle_count + tri_count))
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for its geometry", where);
    float nm[9];
    int flip = normal_matrix(xform, nm) < 0.0f;
    uint32_t base = s->vertex_count;
    for (uint32_t v = 0; v < vertex_count; ++v) {
        struct aiVector3D q = {p[v].x, p[v].y, p[v].z};
        s->positions[base + v] = xform_point(xform, q);
        if (!(fabsf(s->positions[base + v].x) <= IC_SCENE_MAX_COORD &&
              fabsf(s->positions[base + v].y) <= IC_SCENE_MAX_COORD &&
              fabsf(s->positions[base + v].z) <= IC_SCENE_MAX_COORD))
            return ic_error_set(err, IC_ERR_INVALID_ARG,
                                "%s: the transform takes a vertex beyond the largest coordinate %g; give a smaller "
                                "scale or translation",
                                where, (double)IC_SCENE_MAX_COORD);
        if (s->normals) {
            struct aiVector3D nn = n ? (struct aiVector3D){n[v].x, n[v].y, n[v].z} : (struct aiVector3D){0, 0, 0};
            s->normals[base + v] = n ? xform_normal(nm, nn) : v3s(0.0f);
        }
        if (s->uvs)
            s->uvs[2 * (base + v)] = s->uvs[2 * (base + v) + 1] = 0.0f;
    }
    s->vertex_count += vertex_count;
    for (uint32_t f = 0; f < tri_count; ++f) {
        uint32_t i0 = base + tri[3 * f], i1 = base + tri[3 * f + (flip ? 2 : 1)], i2 = base + tri[3 * f + (flip ? 1 : 2)];
        if (is_degenerate(s->positions[i0], s->positions[i1], s->positions[i2])) {
            drop_degenerate(b, where);
            ++b->material_dropped[material];
            continue;
        }
        uint32_t t = s->triangle_count++;
        s->triangles[3 * t] = i0;
        s->triangles[3 * t + 1] = i1;
        s->triangles[3 * t + 2] = i2;
        s->triangle_material[t] = material;
        ++b->material_tris[material];
    }
    return IC_OK;
}

ic_result ic_mesh_import(ic_scene_builder *b, const char *mesh_path, const float *xform, const char *xform_where,
                         ic_error *err)
{
    ic_scene *s = b->scene;
    mesh_source src;
    ic_result r = source_load(mesh_path, &src, err);
    if (r != IC_OK)
        return r;
    char ext[16], dir[IC_SCENE_PATH_MAX];
    ic_path_extension(src.name, ext, sizeof ext);
    ic_path_dirname(mesh_path, dir, sizeof dir);
    int is_gltf = !strcmp(ext, ".gltf") || !strcmp(ext, ".glb");
    char tex_dir[IC_SCENE_PATH_MAX];
    if (!strcmp(ext, ".obj"))
        obj_material_dir(&src, dir, tex_dir, sizeof tex_dir);
    else
        snprintf(tex_dir, sizeof tex_dir, "%s", dir);
    if ((!strcmp(ext, ".obj") &&
         ((r = run_check_max(&src, ic_obj_check, ic_scene_max_mesh_elements(b->opt), err)) != IC_OK ||
          (r = check_obj_materials(b, &src, dir, err)) != IC_OK)) ||
        (!strcmp(ext, ".ply") && (r = run_check_max(&src, ic_ply_check, ic_scene_max_mesh_elements(b->opt), err)) != IC_OK) ||
        (!strcmp(ext, ".glb") && (r = run_check(&src, ic_glb_check, err)) != IC_OK) ||
        (!strcmp(ext, ".gltf") && (r = run_check(&src, ic_gltf_check, err)) != IC_OK)) {
        free(src.data);
        return r;
    }
    source_fs fs = {&src, b, ""};
    /* read only: the steps follow once the mirrored placements are known (below) */
    const struct aiScene *ai = source_import(&src, &fs, 0);
    if (fs.refused[0]) { /* assimp may have failed for it, or carried on without it (an MTL file) */
        r = check_named_file(b, mesh_path, "file", fs.refused, err);
        if (ai)
            aiReleaseImport(ai);
        free(src.data);
        return r;
    }
    if (!ai) {
        free(src.data);
        return ic_error_set(err, IC_ERR_PARSE, "%s: cannot import the mesh (%s); check that it is a valid OBJ, glTF "
                                               "or PLY file",
                            mesh_path, aiGetErrorString());
    }
    /* assimp's steps in the order one call would run them: PreTransformVertices merges the meshes of one
     * material and vertex format into one in world space (the node hierarchy baked in), Triangulate, then
     * JoinIdenticalVertices joins the vertices the merged meshes share; between the first two, the faces of
     * the placements that mirror get their winding swapped, which PreTransformVertices leaves as it was */
    mesh_instance *inst = NULL;
    size_t inst_count = 0;
    unsigned merged = 0;
    if ((r = check_finite_vertices(ai, mesh_path, err)) != IC_OK ||
        (r = collect_instances(ai, mesh_path, &inst, &inst_count, &merged, err)) != IC_OK) {
        aiReleaseImport(ai);
        free(src.data);
        return r;
    }
    /* with nothing to merge PreTransformVertices would throw, and assimp would then release the scene twice */
    if (ai->mNumMeshes > 0 && merged == 0) {
        free(inst);
        aiReleaseImport(ai);
        free(src.data);
        return ic_error_set(err, IC_ERR_PARSE,
                            "%s: cannot import the mesh (no node of the file holds one of its meshes); check that it "
                            "is a valid OBJ, glTF or PLY file",
                            mesh_path);
    }
    if ((ai = aiApplyPostProcessing(ai, aiProcess_PreTransformVertices)) != NULL &&
        (r = flip_mirrored(ai, inst, inst_count, merged, mesh_path, err)) != IC_OK) {
        free(inst);
        aiReleaseImport(ai);
        free(src.data);
        return r;
    }
    free(inst);
    /* no aiProcess_Triangulate: assimp 5.2's ear clipping turns concave polygons of five or more corners into
     * triangles that leave the outline and overlap (an L-shaped hexagon of area 3 covered 4); append_meshes
     * triangulates polygons itself (ic_tess_polygon) */
    if (!ai || !(ai = aiApplyPostProcessing(ai, aiProcess_JoinIdenticalVertices))) {
        free(src.data);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for assimp's processing of the mesh", mesh_path);
    }
    float *strengths = NULL;
    /* tangents only for a file with a normal map: MikkTSpace-like ones where the file gives none */
    int normal_mapped = 0;
    for (unsigned i = 0; i < ai->mNumMaterials; ++i)
        normal_mapped |= aiGetMaterialTextureCount(ai->mMaterials[i], aiTextureType_NORMALS) > 0;
    /* A failed step has released the scene and leaves aiGetErrorString() as it was: the last failed import's
     * text, another file's or none, so it is not quoted. The tangent step fails only when memory runs out:
     * missing normals or texture coordinates, or degenerate ones, it answers with no or default tangents. */
    if (normal_mapped)
        lead_with_corner(ai);
    if (normal_mapped && !(ai = aiApplyPostProcessing(ai, aiProcess_CalcTangentSpace))) {
        free(src.data);
        return ic_error_set(err, IC_ERR_OOM,
                            "%s: out of memory computing the tangents of the normal-mapped mesh (assimp's "
                            "CalcTangentSpace step failed); free memory, or remove the normal maps from its materials",
                            mesh_path);
    }
    if ((ai->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || ai->mNumMeshes == 0) {
        r = ic_error_set(err, IC_ERR_PARSE, "%s: the file holds no triangle mesh; export the geometry as triangles",
                         mesh_path);
        goto done;
    }

    uint32_t material_base = s->material_count;
    uint32_t nmat = ai->mNumMaterials ? ai->mNumMaterials : 1;
    if (is_gltf)
        strengths = gltf_emissive_strengths(&src, ai);
    char *path_copy = malloc(strlen(mesh_path) + 1);
    if (path_copy)
        memcpy(path_copy, mesh_path, strlen(mesh_path) + 1);
    if (!path_copy || !grow((void **)&b->mesh_paths, sizeof *b->mesh_paths, b->mesh_count + 1)) {
        free(path_copy);
        r = ic_error_set(err, IC_ERR_OOM, "%s: out of memory", mesh_path);
        goto done;
    }
    b->mesh_paths[b->mesh_count++] = path_copy;
    if (!grow((void **)&s->materials, sizeof *s->materials, material_base + nmat) ||
        !grow((void **)&b->material_dropped, sizeof *b->material_dropped, material_base + nmat) ||
        !grow((void **)&b->material_tris, sizeof *b->material_tris, material_base + nmat) ||
        !grow((void **)&b->material_mesh, sizeof *b->material_mesh, material_base + nmat)) {
        r = ic_error_set(err, IC_ERR_OOM, "%s: out of memory for its materials", mesh_path);
        goto done;
    }
    char unread_first[UNREAD_KINDS][128] = {{0}}; /* the first material with each unread texture feature */
    for (uint32_t i = 0; i < nmat; ++i) {
        ic_material *m = &s->materials[material_base + i];
        b->material_dropped[material_base + i] = 0;
        b->material_tris[material_base + i] = 0;
        b->material_mesh[material_base + i] = b->mesh_count - 1;
        if (ai->mNumMaterials == 0) {
            memset(m, 0, sizeof *m);
            snprintf(m->name, sizeof m->name, "default");
            m->kd = v3s(0.6f);
            m->kd_texture = -1;
            m->ior = 1.5f;
        } else {
            float one = 1.0f;
            const float *strength = !is_gltf ? NULL : (strengths ? &strengths[i] : &one);
            r = convert_material(b, ai, ai->mMaterials[i], strength, mesh_path, dir, tex_dir, m, err);
            if (r != IC_OK)
                goto done;
            unsigned found = unread_texture_features(ai->mMaterials[i], is_gltf);
            for (int k = 0; k < UNREAD_KINDS; ++k)
                if ((found >> k & 1) && !unread_first[k][0])
                    snprintf(unread_first[k], sizeof unread_first[k], "%s", m->name[0] ? m->name : "(unnamed)");
        }
        ++s->material_count;
    }
    warn_unread_texture_features(s, mesh_path, (const char(*)[128])unread_first);

    float identity[16];
    ic_mat4_identity(identity);
    uint32_t tris_before = s->triangle_count, dropped_before = s->dropped_degenerate;
    r = append_meshes(b, ai, mesh_path, xform ? xform : identity, xform_where, material_base, normal_mapped, err);
    if (r == IC_OK && s->triangle_count == tris_before)
        r = ic_error_set(err, IC_ERR_PARSE,
                         "%s: no usable triangle (%u of zero area dropped; points and lines are ignored); fix the "
                         "geometry or remove the mesh",
                         mesh_path, s->dropped_degenerate - dropped_before);
done:
    free(strengths);
    aiReleaseImport(ai);
    free(src.data);
    return r;
}
