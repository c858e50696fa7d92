/*
 * ilf/limits.h - every limit on what ilfkit's files and libraries read, in
 * one place, each with the reason for its value (after SQLite's
 * sqliteLimit.h); the limits of the `ilf` command's own options are the
 * tools' (tools/cli_limits.h).
 *
 * A limit here bounds what an input may ask for: a reader refuses anything
 * beyond it with an error naming the file and the limit, so a hostile or
 * mistaken input costs time and memory in proportion to its size, never more
 * (docs/robustness.md). Public headers that promise a limit to library users
 * (lfio's LFIO_SLAB_MAX_N, ...) keep their own names; where one of those is the
 * same quantity, it is defined from the value here or checked against it.
 *
 * Units: bytes unless a name says otherwise; counts are plain numbers.
 */
#ifndef ILF_LIMITS_H
#define ILF_LIMITS_H

#include <stdint.h>

/* Worker threads in one team. "0 = every core" asks for the online cores; no machine that runs a
 * 2026 build has more, and each thread costs a stack (8 MiB of address space) and a scratch buffer. */
#define ILF_MAX_THREADS 1024u

/* Bytes of one error message a library owns (per thread). A message names one file and one problem;
 * a longer one is cut at this length, never overrun. */
#define ILF_MESSAGE_BYTES 1024u

/* Pixels along either side of an image read or written (image/image.h). Far beyond any light probe or
 * view ilf makes, small enough that width * height * 4 channels of float stays addressable. */
#define ILF_IMAGE_MAX_SIDE 65536

/* Pixels along either side of a camera's image (a scene's "camera", relight/camera.h, `ilf view`): 16384^2
 * pixels of float RGB are 3 GiB, the most a view should ask of a workstation. */
#define ILF_CAMERA_MAX_SIDE 16384u

/* Samples (width * height * channels) of one image read: 8 GiB of float. A corrupt or hostile header
 * cannot make the reader allocate more than this, whatever sides it claims. */
#define ILF_IMAGE_MAX_SAMPLES (1LL << 31)

/* ------------------------------------------------------------ JSON (ilf/json.h) */

/* Arrays and objects open at once in a JSON file. cJSON parses recursively, one stack frame per level:
 * 1000 levels fit any thread's stack (cJSON's own CJSON_NESTING_LIMIT is the same) and no scene,
 * manifest or glTF file nests more than about 10 deep. */
#define ILF_JSON_MAX_DEPTH 1000

/* Bytes of a scene file. The whole file is read and parsed in memory (the tree costs several times
 * the text); the largest hand-written or generated scene is a few MiB, its meshes live in files of
 * their own. */
#define ILF_SCENE_MAX_BYTES ((size_t)256 << 20)

/* Bytes of a capture manifest: a grid and a few settings per position, at most
 * CAP__MAX_POSITIONS of them, fits in well under this. capture.h promises it to library users as
 * CAP_MANIFEST_MAX_BYTES; manifest.c checks that the two agree. */
#define ILF_MANIFEST_MAX_BYTES ((size_t)64 << 20)

/* Bytes of a proxy's JSON list of rectangles (at most CAP_PROXY_MAX of them). */
#define ILF_PROXY_JSON_MAX_BYTES ((size_t)16 << 20)

/* ------------------------------------------------------------ meshes (ilf/mesh.h) */

/* Polygons, and vertices, one scene may hold (2^26): 64 Mi polygons already take gigabytes in the
 * engine's structures, and every index fits in 32 bits with room to spare. */
#define ILF_MESH_MAX_ELEMENTS ((size_t)1 << 26)

/* Vertices of one polygon or mesh face: the scene loader's scratch arrays are this long, and a
 * convex face with more corners than this is a mistake or an attack, not a lamp. */
#define ILF_MESH_MAX_FACE_VERTICES 4096u

/* Passes of the merging of coplanar mesh faces (relight/src/mesh.c): a pass sorts every edge, and
 * joins a face at most once, so a flat grid of 180,000 triangles needs 20 passes (halving the
 * faces at each) where a file built to join one pair a pass would take one pass per face. */
#define ILF_MESH_MERGE_MAX_PASSES 64

/* Bytes of a glTF file's JSON read by the accessor pre-check (.gltf: the whole file; .glb: its JSON
 * chunk). Parsing costs several times this in memory; a GLB whose JSON chunk is larger is refused,
 * a larger .gltf is left to assimp unchecked. */
#define ILF_GLTF_JSON_MAX_BYTES ((size_t)1 << 28)

/* Elements declared in a PLY header (vertex, face, ...): real files have two or three. */
#define ILF_PLY_MAX_ELEMENTS 32

/* Properties of one PLY element: positions, normals, colours and texture coordinates make about 12. */
#define ILF_PLY_MAX_PROPERTIES 64

/* Words on one PLY header line ("property list uchar int vertex_indices" has 5). */
#define ILF_PLY_MAX_WORDS 6

/* ------------------------------------------------------------ capture */

/* Light probe positions one manifest may describe (2^20): a capture grid of 1024 x 1024 probes is far
 * beyond any rig, and the position table stays a few tens of MiB. */
#define ILF_CAPTURE_MAX_POSITIONS ((uint64_t)1 << 20)

/* Images in one exposure bracket (capture.h's CAP_BRACKET_MAX): HDR merges use 3 to 9; each image of a
 * bracket is held in memory while the bracket is merged. */
#define ILF_CAPTURE_MAX_BRACKET 16u

/* Image samples (width * height * channels) one capture reads in all, over every image it decodes, an image
 * named again (at another position or in a bracket) counted each time it is read: 2^36, some 700 probes of
 * 8192 x 4096 RGB, a large rig's brackets. The positions, brackets and each image's size are bounded above,
 * but together they could ask for 2^55 samples from one small, highly compressed image named at every
 * position; each sample is decoded, repaired and resampled, so the total is checked from the images' headers
 * before any is decoded (the same 2^36 as a slab's radiance bytes, LFIO_SLAB_MAX_BYTES). */
#define ILF_CAPTURE_MAX_SAMPLES ((uint64_t)1 << 36)

/* Capture planes one manifest may name (each becomes a slab): a box around a fixture needs 5 or 6; every
 * reprojected ray is traced back to every plane, so the work grows with their number. */
#define ILF_CAPTURE_MAX_PLANES 64u

/* Bytes of a file path a manifest may build (a directory joined with a file name or an expanded
 * pattern): PATH_MAX on Linux less its terminator. */
#define ILF_PATH_MAX_BYTES 4095

/* Pixels along either side of a rendered light probe (capture's renderer, `ilf render-probes --size`):
 * 16384^2 float RGB is 3 GiB, more than any probe grid needs. */
#define ILF_PROBE_MAX_SIDE 16384

/* Probes along either side of a rendered grid (`ilf render-probes --grid`): 1024^2 probes already
 * exceeds ILF_CAPTURE_MAX_POSITIONS. */
#define ILF_PROBE_MAX_GRID 1024u

/* Stratified sub-samples per axis and pixel when rendering a probe: 64^2 = 4096 rays a pixel, past the
 * point where more rays change an 8-bit or half-float image. */
#define ILF_PROBE_MAX_STRATA 64u

/* Proxy rectangles one depth correction may use (reproject.h's CAP_PROXY_MAX): each is tested against
 * every reprojected ray, so the work grows with their number; rooms need tens. */
#define ILF_PROXY_MAX_RECTANGLES 4096u

/* Stratified directions per axis per solid angle when reprojecting (16^2 = 256 a solid angle): beyond
 * it the error is the proxy's, not the sampling's. */
#define ILF_REPROJECT_MAX_STRATA 16u

/* Pixels of all the probes one `ilf render-probes` writes (grid positions times pixels a probe): 2^32,
 * 48 GiB of float EXR on disk. The grid and the probe size are each bounded above, but together they
 * could ask for petabytes; this is checked before the scene is relit. */
#define ILF_PROBE_MAX_PIXELS ((uint64_t)1 << 32)

/* Rays one `ilf render-probes` traces (pixels of all probes times strata^2): 2^38, hours of tracing on
 * a small machine already. Checked with ILF_PROBE_MAX_PIXELS, before any work. */
#define ILF_PROBE_MAX_RAYS ((uint64_t)1 << 38)

/* Bytes of radiance of a whole light field that `ilf reproject` builds, over every proxy rectangle: the
 * slabs are held in memory until the file is written, so a small proxy file naming many large
 * rectangles must not start (the same 64 GiB as one slab's limit, LFIO_SLAB_MAX_BYTES). */
#define ILF_REPROJECT_MAX_BYTES ((uint64_t)1 << 36)

/* Stratified directions one `ilf reproject` traces in all (values of every output slab times strata^2):
 * 2^40. Checked with ILF_REPROJECT_MAX_BYTES, before any work. */
#define ILF_REPROJECT_MAX_RAYS ((uint64_t)1 << 40)

/* ------------------------------------------------------------ relight */

/* Vertices of one scene polygon. Larger convex faces are split into fans of polygons this size; the
 * engine's clipping buffers on the stack are sized by it. */
#define ILF_POLYGON_MAX_VERTICES 64

/* Radiance-map cells one scene may have in all (2^26): about 3 GiB of accumulators; the same bound as
 * a radiance-map file's (lfio/radmap.h, LFIO_RADMAP_MAX_CELLS), so every solved scene can be written. */
#define ILF_MAP_MAX_CELLS ((uint64_t)1 << 26)

/* Largest emission a material may have, W sr^-1 m^-2 (relight.h's RL_MAX_EMISSION): irradiance sums of
 * such emitters stay far inside float32, the type of the radiance maps. */
#define ILF_MAX_EMISSION 1e30

#endif /* ILF_LIMITS_H */
