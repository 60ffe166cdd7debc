/* A bare C loop over Embree, to tell the library's own speed from inimtrace's overhead on it.
 *
 * It reads what `inimtrace bench --backends --embree-input DIR` gave Embree for one scene
 * (DIR/<scene>.embree-input: the single-precision triangles, the camera rays and which runs of
 * 16 rays inimtrace traces as packets) and makes the same calls the same way: a robust scene of
 * medium build quality, one triangle geometry per mesh; nearest hits in batches of 2,160 rays
 * (one LCD row) shared out to the threads, each run of 16 rays as one `rtcIntersect16` with the
 * coherent hint or as 16 `rtcIntersect1` as inimtrace's plan says; occlusion as `rtcOccluded1`
 * with tfar = 1e4 per ray. The same source compiles against Embree 3 (the system's
 * <embree3/rtcore.h>) or, with -DINIM_EMBREE4, Embree 4 (the headers of the embree4-sys crate,
 * as inimtrace's feature `embree4` uses them, hit records padded for Embree 4.3+'s longer ones).
 * scripts/embree-bare.sh builds both and runs them alternately.
 *
 * Usage: embree-bare INPUT[,INPUT...] [THREADS [DEVICE_CONFIG [MODE]]]
 *   Several inputs are measured one after the other in one process, each on a new device, as
 *   `bench --backends` measures its scenes.
 *   MODE: plan (inimtrace's packet plan, the default), packets (every run a packet), single.
 * Variations for measuring one choice at a time (environment): EMBREE_BARE_FEATURES=triangle
 * (Embree 4's feature mask RTC_FEATURE_FLAG_TRIANGLE instead of all), EMBREE_BARE_FLAGS=none
 * (no RTC_SCENE_FLAG_ROBUST), EMBREE_BARE_QUALITY=low|high (instead of medium),
 * EMBREE_BARE_PAUSE_MS=N (sleep N ms between the build and the first query, to let the build's
 * worker threads go idle), EMBREE_BARE_PASSES=N (timed passes after the first of each query,
 * default 41, about 0.5 s as `bench --backends` times: the rates reported are the median of
 * those passes, and the first pass right after the build is reported beside them as
 * *_cold_rays_per_s), EMBREE_BARE_HINT=incoherent
 * (packets without the coherent-rays hint), EMBREE_BARE_WIDTH=8 (each packet of 16 traced as two
 * rtcIntersect8).
 * Prints one line of `key=value`: library version, seconds to create the device, to build
 * (geometries and rtcCommitScene), nearest-hit and occlusion rays per second, hit counts and a
 * checksum of the hits (equal between the two libraries when they find the same hits). */
#define _GNU_SOURCE
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef INIM_EMBREE4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#define BATCH 2160

struct Mesh { uint32_t nv, nt; float *v; uint32_t *t; };
struct Input { uint32_t nmesh; struct Mesh *mesh; uint32_t nray; float *ray; uint8_t *plan; };

static void die(const char *what) { fprintf(stderr, "embree-bare: %s\n", what); exit(1); }

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void take(FILE *f, void *p, size_t n) { if (fread(p, 1, n, f) != n) die("input file is truncated"); }
static uint32_t take_u32(FILE *f) { uint32_t x; take(f, &x, 4); return x; }
static void *alloc(size_t n) { void *p = aligned_alloc(64, (n + 63) / 64 * 64 + 64); if (!p) die("out of memory"); return p; }

static struct Input load(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) die("cannot open the input file");
    char magic[8];
    take(f, magic, 8);
    if (memcmp(magic, "INIMEMB1", 8)) die("not an inimtrace Embree input (INIMEMB1)");
    struct Input in;
    in.nmesh = take_u32(f);
    in.mesh = calloc(in.nmesh, sizeof *in.mesh);
    for (uint32_t g = 0; g < in.nmesh; g++) {
        struct Mesh *m = &in.mesh[g];
        m->nv = take_u32(f);
        m->nt = take_u32(f);
        m->v = alloc(12 * (size_t)m->nv);
        m->t = alloc(12 * (size_t)m->nt);
        take(f, m->v, 12 * (size_t)m->nv);
        take(f, m->t, 12 * (size_t)m->nt);
    }
    in.nray = take_u32(f);
    in.ray = alloc(32 * (size_t)in.nray);
    take(f, in.ray, 32 * (size_t)in.nray);
    in.plan = alloc((in.nray + 15) / 16);
    take(f, in.plan, (in.nray + 15) / 16);
    fclose(f);
    return in;
}

/* Embree 4.3+ writes more of a hit than the 4.2 headers declare: spare bytes after each record. */
struct Hit1 { struct RTCRayHit rh; char spare[128]; } __attribute__((aligned(64)));
struct Hit16 { struct RTCRayHit16 rh; char spare[128]; } __attribute__((aligned(64)));

static RTCScene scene;
static struct Input in;
static int mode; /* 0 plan, 1 packets, 2 single */
static int triangle_features; /* Embree 4: feature mask RTC_FEATURE_FLAG_TRIANGLE */
static int incoherent_packets, width8;
static atomic_uint next_batch;
struct Count { uint64_t hits, sum; };

static void intersect1(struct Hit1 *h) {
#ifdef INIM_EMBREE4
    struct RTCIntersectArguments args;
    rtcInitIntersectArguments(&args);
    if (triangle_features) args.feature_mask = RTC_FEATURE_FLAG_TRIANGLE;
    rtcIntersect1(scene, &h->rh, &args);
#else
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(scene, &ctx, &h->rh);
#endif
}

struct Hit8 { struct RTCRayHit8 rh; char spare[128]; } __attribute__((aligned(64)));

/* Lanes [first, first + 8) of a 16-ray packet as an 8-ray one and back (EMBREE_BARE_WIDTH=8). */
#define COPY8(dst, src, a, b) for (int k = 0; k < 8; k++) dst.a[k] = src.a[k + b]
#define BACK8(dst, src, a, b) for (int k = 0; k < 8; k++) dst.a[k + b] = src.a[k]
#define RAY_FIELDS(X, d, s, f) X(d, s, ray.org_x, f); X(d, s, ray.org_y, f); X(d, s, ray.org_z, f); \
    X(d, s, ray.dir_x, f); X(d, s, ray.dir_y, f); X(d, s, ray.dir_z, f); X(d, s, ray.tnear, f); \
    X(d, s, ray.tfar, f); X(d, s, ray.mask, f); X(d, s, hit.geomID, f); X(d, s, hit.instID[0], f)
#define HIT_FIELDS(X, d, s, f) X(d, s, ray.tfar, f); X(d, s, hit.geomID, f); X(d, s, hit.primID, f); \
    X(d, s, hit.u, f); X(d, s, hit.v, f)

static void intersect16(const int *valid, struct Hit16 *h) {
#ifdef INIM_EMBREE4
    struct RTCIntersectArguments args;
    rtcInitIntersectArguments(&args);
    args.flags = incoherent_packets ? RTC_RAY_QUERY_FLAG_INCOHERENT : RTC_RAY_QUERY_FLAG_COHERENT;
    if (triangle_features) args.feature_mask = RTC_FEATURE_FLAG_TRIANGLE;
#define CALL8(valid8, h8) rtcIntersect8(valid8, scene, &h8.rh, &args)
#define CALL16() rtcIntersect16(valid, scene, &h->rh, &args)
#else
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = incoherent_packets ? RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT : RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
#define CALL8(valid8, h8) rtcIntersect8(valid8, scene, &ctx, &h8.rh)
#define CALL16() rtcIntersect16(valid, scene, &ctx, &h->rh)
#endif
    if (!width8) {
        CALL16();
        return;
    }
    for (int b = 0; b < 16; b += 8) {
        struct Hit8 h8;
        int valid8[8] __attribute__((aligned(32)));
        memset(&h8, 0, sizeof h8);
        for (int k = 0; k < 8; k++) valid8[k] = valid[k + b];
        RAY_FIELDS(COPY8, h8.rh, h->rh, b);
        CALL8(valid8, h8);
        HIT_FIELDS(BACK8, h->rh, h8.rh, b);
    }
}

static void count(struct Count *c, unsigned geom, unsigned prim) {
    if (geom == RTC_INVALID_GEOMETRY_ID) return;
    c->hits++;
    c->sum += (uint64_t)geom * 2654435761u + prim;
}

static void run16(uint32_t first, uint32_t m, struct Count *c) {
    const float *r = in.ray + 8 * (size_t)first;
    int packet = mode == 1 || (mode == 0 && in.plan[first / 16]);
    if (!packet) {
        for (uint32_t i = 0; i < m; i++, r += 8) {
            struct Hit1 h;
            memset(&h, 0, sizeof h);
            h.rh.ray = (struct RTCRay){r[0], r[1], r[2], r[6], r[3], r[4], r[5], 0.0f, r[7], 0xffffffffu, 0, 0};
            h.rh.hit.geomID = h.rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            intersect1(&h);
            count(c, h.rh.hit.geomID, h.rh.hit.primID);
        }
        return;
    }
    struct Hit16 h;
    int valid[16] __attribute__((aligned(64)));
    memset(&h, 0, sizeof h);
    for (int k = 0; k < 16; k++) {
        valid[k] = k < (int)m ? -1 : 0;
        h.rh.hit.geomID[k] = h.rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        if (k >= (int)m) continue;
        const float *q = r + 8 * k;
        h.rh.ray.org_x[k] = q[0]; h.rh.ray.org_y[k] = q[1]; h.rh.ray.org_z[k] = q[2];
        h.rh.ray.dir_x[k] = q[3]; h.rh.ray.dir_y[k] = q[4]; h.rh.ray.dir_z[k] = q[5];
        h.rh.ray.tnear[k] = q[6]; h.rh.ray.tfar[k] = q[7]; h.rh.ray.mask[k] = 0xffffffffu;
    }
    intersect16(valid, &h);
    for (uint32_t k = 0; k < m; k++) count(c, h.rh.hit.geomID[k], h.rh.hit.primID[k]);
}

static void *nearest_worker(void *arg) {
    struct Count *c = arg;
    for (;;) {
        uint32_t b = atomic_fetch_add(&next_batch, 1);
        uint64_t first = (uint64_t)b * BATCH;
        if (first >= in.nray) return NULL;
        uint32_t end = first + BATCH < in.nray ? first + BATCH : in.nray;
        for (uint32_t i = first; i < end; i += 16) run16(i, end - i < 16 ? end - i : 16, c);
    }
}

static void *occluded_worker(void *arg) {
    struct Count *c = arg;
    for (;;) {
        uint32_t b = atomic_fetch_add(&next_batch, 1);
        uint64_t first = (uint64_t)b * BATCH;
        if (first >= in.nray) return NULL;
        uint32_t end = first + BATCH < in.nray ? first + BATCH : in.nray;
        for (uint32_t i = first; i < end; i++) {
            const float *r = in.ray + 8 * (size_t)i;
            struct RTCRay ray __attribute__((aligned(16))) = {r[0], r[1], r[2], r[6], r[3], r[4], r[5], 0.0f, 1e4f, 0xffffffffu, 0, 0};
#ifdef INIM_EMBREE4
            rtcOccluded1(scene, &ray, NULL);
#else
            struct RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            rtcOccluded1(scene, &ctx, &ray);
#endif
            if (ray.tfar < 0.0f) c->hits++;
        }
    }
}

/* Runs `worker` on `threads` threads over all rays; returns seconds, adds up the counts. */
static double parallel(void *(*worker)(void *), int threads, struct Count *total) {
    pthread_t tid[64];
    struct Count c[64];
    memset(c, 0, sizeof c);
    atomic_store(&next_batch, 0);
    double t0 = now();
    for (int i = 0; i < threads; i++)
        if (pthread_create(&tid[i], NULL, worker, &c[i])) die("cannot start a thread");
    for (int i = 0; i < threads; i++) pthread_join(tid[i], NULL);
    double t = now() - t0;
    for (int i = 0; i < threads; i++) { total->hits += c[i].hits; total->sum += c[i].sum; }
    return t;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median seconds of `passes` more timed passes of a query (after its first, cold one). */
static double median_pass(void *(*worker)(void *), int threads, int passes) {
    double t[1000];
    for (int k = 0; k < passes; k++) {
        struct Count again = {0, 0};
        t[k] = parallel(worker, threads, &again);
    }
    qsort(t, (size_t)passes, sizeof t[0], cmp_double);
    return t[passes / 2];
}

/* One input, as inimtrace measures one scene: a new device, the build, the queries; one line. */
static void measure(const char *path, int threads, const char *config) {
    in = load(path);
    const char *features = getenv("EMBREE_BARE_FEATURES"), *flags = getenv("EMBREE_BARE_FLAGS");
    const char *quality_name = getenv("EMBREE_BARE_QUALITY");
    triangle_features = features && !strcmp(features, "triangle");
    incoherent_packets = getenv("EMBREE_BARE_HINT") && !strcmp(getenv("EMBREE_BARE_HINT"), "incoherent");
    width8 = getenv("EMBREE_BARE_WIDTH") && !strcmp(getenv("EMBREE_BARE_WIDTH"), "8");
    enum RTCBuildQuality quality = !quality_name ? RTC_BUILD_QUALITY_MEDIUM
        : !strcmp(quality_name, "low") ? RTC_BUILD_QUALITY_LOW
        : !strcmp(quality_name, "high") ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;

    double t0 = now();
    RTCDevice device = rtcNewDevice(config);
    if (!device) die("rtcNewDevice failed");
    double device_s = now() - t0;
    t0 = now();
    scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, flags && !strcmp(flags, "none") ? RTC_SCENE_FLAG_NONE : RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, quality);
    for (uint32_t g = 0; g < in.nmesh; g++) {
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        void *v = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, in.mesh[g].nv);
        void *t = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, in.mesh[g].nt);
        memcpy(v, in.mesh[g].v, 12 * (size_t)in.mesh[g].nv);
        memcpy(t, in.mesh[g].t, 12 * (size_t)in.mesh[g].nt);
        rtcSetGeometryBuildQuality(geom, quality);
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene, geom);
        rtcReleaseGeometry(geom);
    }
    rtcCommitScene(scene);
    double build_s = now() - t0;
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) die("Embree reported an error");

    const char *pause = getenv("EMBREE_BARE_PAUSE_MS");
    if (pause) {
        long ms = atol(pause);
        struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
        nanosleep(&ts, NULL);
    }
    const char *passes_env = getenv("EMBREE_BARE_PASSES");
    int passes = passes_env ? atoi(passes_env) : 41;
    if (passes < 1 || passes > 1000) die("EMBREE_BARE_PASSES must be 1 to 1000");
    struct Count near = {0, 0}, occ = {0, 0};
    double near_cold = parallel(nearest_worker, threads, &near);
    double near_s = median_pass(nearest_worker, threads, passes);
    double occ_cold = parallel(occluded_worker, threads, &occ);
    double occ_s = median_pass(occluded_worker, threads, passes);
    printf("library=%ld device_s=%.4f build_s=%.4f rays=%u nearest_rays_per_s=%.0f nearest_cold_rays_per_s=%.0f "
           "hits=%lu checksum=%lu occluded_rays_per_s=%.0f occluded_cold_rays_per_s=%.0f occluded=%lu\n",
           (long)rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION), device_s, build_s, in.nray,
           in.nray / near_s, in.nray / near_cold, (unsigned long)near.hits, (unsigned long)near.sum,
           in.nray / occ_s, in.nray / occ_cold, (unsigned long)occ.hits);
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
    for (uint32_t g = 0; g < in.nmesh; g++) { free(in.mesh[g].v); free(in.mesh[g].t); }
    free(in.mesh); free(in.ray); free(in.plan);
}

int main(int argc, char **argv) {
    if (argc < 2) die("usage: embree-bare INPUT[,INPUT...] [THREADS [DEVICE_CONFIG [plan|packets|single]]]");
    int threads = argc > 2 ? atoi(argv[2]) : 2;
    if (threads < 1 || threads > 64) die("THREADS must be 1 to 64");
    const char *config = argc > 3 ? argv[3] : "";
    mode = argc > 4 ? (!strcmp(argv[4], "packets") ? 1 : !strcmp(argv[4], "single") ? 2 : 0) : 0;
    /* Several inputs, comma-separated, are measured one after the other in this one process. */
    for (char *path = strtok(argv[1], ","); path; path = strtok(NULL, ",")) measure(path, threads, config);
    return 0;
}
