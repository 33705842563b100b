/* Bulk position/velocity/force I/O for YADE 2023.02a, without YADE's headers.
 *
 * YADE's Python API moves one body per call (O.forces.addF, b.state.pos); this library moves
 * arrays of bodies per call, for ctypes and numba callers. It declares nothing of YADE's classes:
 *   - functions are YADE's own exported C++ symbols, looked up with dlsym in the libyade.so that
 *     the process already has loaded (RTLD_NOLOAD), and called with `this` passed explicitly
 *     (Itanium C++ ABI); Eigen::Matrix<double,3,1> is three contiguous doubles;
 *   - the few data offsets (ForceContainer in Scene, its summed forces' data pointer, BodyContainer
 *     pointer in Scene, State pointer in Body, pos/vel/angVel in State) are not compiled in: the
 *     Python side discovers them by probing a scratch scene and hands them over with
 *     yb_configure() only after it has verified them (engines/yade/yadebulk/probe.py). Until then
 *     every bulk function returns YB_ENOTREADY.
 *
 * Every bulk function takes (const int64_t *ids, int64_t n, double *array), checks every id
 * against the current scene's body count and for a live body before it reads or writes anything,
 * and returns 0, a negative YB_E* code, or k >= 1 when ids[k-1] is out of range or erased.
 * Forces and torques go through ForceContainer::addForce/addTorque/setPermForce, the functions
 * O.forces.addF/addT/setPermF call, so YADE's per-thread buffers and sync flags behave as theirs;
 * yb_add_force_unsynced_xz adds as ForceContainer::addForceUnsynced does (see there).
 * yb_steps (steps.cpp, C++ to catch what YADE throws) is O.step(): Scene::moveToNextTimeStep.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define YB_ENOTREADY (-1) /* not opened or layout not verified */
#define YB_ENOSCENE (-2)  /* no current scene or body container */
#define YB_EBADN (-3)     /* n < 0 */
#define YB_ENOMEM (-5)    /* no memory for the ids' lookup */

/* C++ signatures, `this` first (mangled names in yb_open). References are returned as pointers. */
typedef void *(*omega_instance_fn)(void);              /* Omega& Singleton<Omega>::instance() */
typedef void *const *(*get_scene_fn)(const void *);    /* const shared_ptr<Scene>& Omega::getScene() const */
typedef void *const *(*body_by_id_fn)(int, void *);    /* const shared_ptr<Body>& Body::byId(int, Scene*) */
typedef size_t (*bodies_size_fn)(const void *);        /* size_t BodyContainer::size() const */
typedef void *const *(*bodies_at_fn)(void *, unsigned); /* shared_ptr<Body>& BodyContainer::operator[](unsigned) */
typedef void (*force_fn)(void *, int, const double *); /* void ForceContainer::xxx(int, const Vector3r&) */
typedef void (*scene_step_fn)(void *);                 /* void Scene::moveToNextTimeStep() */
typedef void (*sync_sizes_fn)(void *);                 /* void ForceContainer::syncSizesOfContainers() */

static struct {
    omega_instance_fn omega;
    get_scene_fn get_scene;
    body_by_id_fn body_by_id;
    bodies_size_fn bodies_size;
    bodies_at_fn bodies_at;
    force_fn add_force, add_torque, set_perm_force, add_force_unsynced;
    sync_sizes_fn sync_sizes;
    scene_step_fn scene_step;
} Y;

static struct {
    ptrdiff_t forces, force_data, bodies, state, pos, vel, angvel; /* byte offsets, see yb_configure */
    int ready;
} L;

static char error_text[512];

const char *yb_error(void) { return error_text; }

void yb_set_error(const char *text) { snprintf(error_text, sizeof error_text, "%s", text); }

/* Resolve YADE's functions in the libyade.so already loaded at `path`. 0 or YB_ENOTREADY. */
int yb_open(const char *path)
{
    static const struct { const char *name; void **slot; } symbols[] = {
        {"_ZN9SingletonIN4yade5OmegaEE8instanceEv", (void **)&Y.omega},
        {"_ZNK4yade5Omega8getSceneEv", (void **)&Y.get_scene},
        {"_ZN4yade4Body4byIdEiPNS_5SceneE", (void **)&Y.body_by_id},
        {"_ZNK4yade13BodyContainer4sizeEv", (void **)&Y.bodies_size},
        {"_ZN4yade13BodyContainerixEj", (void **)&Y.bodies_at},
        {"_ZN4yade14ForceContainer8addForceEiRKN5Eigen6MatrixIdLi3ELi1ELi0ELi3ELi1EEE", (void **)&Y.add_force},
        {"_ZN4yade14ForceContainer9addTorqueEiRKN5Eigen6MatrixIdLi3ELi1ELi0ELi3ELi1EEE", (void **)&Y.add_torque},
        {"_ZN4yade14ForceContainer12setPermForceEiRKN5Eigen6MatrixIdLi3ELi1ELi0ELi3ELi1EEE",
         (void **)&Y.set_perm_force},
        {"_ZN4yade14ForceContainer16addForceUnsyncedEiRKN5Eigen6MatrixIdLi3ELi1ELi0ELi3ELi1EEE",
         (void **)&Y.add_force_unsynced},
        {"_ZN4yade14ForceContainer21syncSizesOfContainersEv", (void **)&Y.sync_sizes},
        {"_ZN4yade5Scene18moveToNextTimeStepEv", (void **)&Y.scene_step},
    };
    L.ready = 0;
    void *lib = dlopen(path, RTLD_NOW | RTLD_NOLOAD);
    if (!lib) {
        snprintf(error_text, sizeof error_text, "%s is not loaded in this process (import yade first)", path);
        return YB_ENOTREADY;
    }
    for (size_t i = 0; i < sizeof symbols / sizeof symbols[0]; i++) {
        *symbols[i].slot = dlsym(lib, symbols[i].name);
        if (!*symbols[i].slot) {
            snprintf(error_text, sizeof error_text, "libyade.so exports no %s", symbols[i].name);
            Y.omega = NULL;
            return YB_ENOTREADY;
        }
    }
    return 0;
}

/* The current Scene* (Omega::instance().getScene().get()), or NULL. */
void *yb_scene(void)
{
    if (!Y.omega) return NULL;
    void *const *scene = Y.get_scene(Y.omega());
    return scene ? scene[0] : NULL;
}

/* Probe helpers on YADE's own functions. Body::byId does no range check: the caller (the probe)
 * passes only ids of bodies it created in its scratch scene. */
void *yb_body_slot(int id) { void *s = yb_scene(); return s ? (void *)Y.body_by_id(id, s) : NULL; }
int64_t yb_bodies_size(const void *bodies) { return bodies ? (int64_t)Y.bodies_size(bodies) : -1; }
void *yb_bodies_at(void *bodies, unsigned id) { return bodies ? (void *)Y.bodies_at(bodies, id) : NULL; }

/* Accept the verified offsets (bytes): Scene -> ForceContainer (embedded), ForceContainer -> the
 * data pointer of its summed forces (std::vector<Vector3r>, the one addForceUnsynced adds to; < 0:
 * unknown, that function is called), Scene -> BodyContainer* (first word of a shared_ptr), Body ->
 * State* (first word of a shared_ptr), State -> pos, vel, angVel (three doubles each). ready = 0
 * withdraws them. */
void yb_configure(int64_t forces, int64_t force_data, int64_t bodies, int64_t state, int64_t pos, int64_t vel,
                  int64_t angvel, int ready)
{
    L.forces = forces, L.force_data = force_data, L.bodies = bodies, L.state = state, L.pos = pos, L.vel = vel;
    L.angvel = angvel;
    L.ready = ready && Y.omega;
}

int yb_ready(void) { return L.ready; }

/* Scene::moveToNextTimeStep, for yb_steps (steps.cpp); NULL before yb_open succeeded. */
scene_step_fn yb_scene_step(void) { return Y.omega ? Y.scene_step : NULL; }

typedef struct {
    char *scene;
    void *bodies;
    int64_t n_bodies;
    char *slots; /* &body[0] of the BodyContainer's vector of shared_ptr<Body>, or NULL */
} Ctx;

#define SLOT_BYTES 16 /* sizeof(shared_ptr<Body>) */

static int begin(Ctx *c, int64_t n)
{
    if (!L.ready) return YB_ENOTREADY;
    if (n < 0) return YB_EBADN;
    c->scene = yb_scene();
    if (!c->scene) return YB_ENOSCENE;
    c->bodies = *(void **)(c->scene + L.bodies);
    if (!c->bodies) return YB_ENOSCENE;
    c->n_bodies = (int64_t)Y.bodies_size(c->bodies);
    /* the bodies' slots indexed directly when the first and the last lie one vector apart, as in
     * YADE's BodyContainer (std::vector<shared_ptr<Body>>); else body by body through YADE */
    c->slots = NULL;
    if (c->n_bodies > 0) {
        char *first = (char *)Y.bodies_at(c->bodies, 0u);
        char *last = (char *)Y.bodies_at(c->bodies, (unsigned)(c->n_bodies - 1));
        if (last == first + (c->n_bodies - 1) * SLOT_BYTES) c->slots = first;
    }
    return 0;
}

/* The State of body `id`, or NULL if out of range, erased or stateless. */
static char *state_of(const Ctx *c, int64_t id)
{
    if (id < 0 || id >= c->n_bodies) return NULL;
    char *slot = c->slots ? c->slots + id * SLOT_BYTES : (char *)Y.bodies_at(c->bodies, (unsigned)id);
    char *body = *(char *const *)slot;
    return body ? *(char **)(body + L.state) : NULL;
}

/* The States of the bodies of one call, looked up once: the checks pass, then the reads or writes
 * (thread-local: a numba caller may hold no GIL). Grown as needed, never freed. */
static __thread char **states;
static __thread int64_t states_cap;

/* 0 with states[k] the State of body ids[k] for every k, YB_ENOMEM, or k >= 1 for the first bad
 * ids[k-1] (out of range, erased or stateless). */
static int64_t look_up(const Ctx *c, const int64_t *ids, int64_t n)
{
    if (n > states_cap) {
        char **grown = realloc(states, (size_t)n * sizeof *states);
        if (!grown) return YB_ENOMEM;
        states = grown, states_cap = n;
    }
    for (int64_t k = 0; k < n; k++)
        if (!(states[k] = state_of(c, ids[k]))) return k + 1;
    return 0;
}

#define BULK_PROLOGUE                                                                                   \
    Ctx c;                                                                                              \
    int64_t err = begin(&c, n);                                                                         \
    if (err || (err = look_up(&c, ids, n))) return err;

/* out[k] = (x, z) of the Vector3r at byte `offset` in body ids[k]'s State */
static int64_t get_xz(ptrdiff_t offset, const int64_t *ids, int64_t n, double *out)
{
    BULK_PROLOGUE
    for (int64_t k = 0; k < n; k++) {
        const double *v = (const double *)(states[k] + offset);
        out[2 * k] = v[0], out[2 * k + 1] = v[2];
    }
    return 0;
}

/* out[k] = (x, z) of pos of body ids[k] */
int64_t yb_get_pos_xz(const int64_t *ids, int64_t n, double *out) { return get_xz(L.pos, ids, n, out); }

/* out[k] = (x, z) of vel of body ids[k] */
int64_t yb_get_vel_xz(const int64_t *ids, int64_t n, double *out) { return get_xz(L.vel, ids, n, out); }

/* vel of body ids[k] = (V[k,0], 0, V[k,1]) */
int64_t yb_set_vel_xz(const int64_t *ids, int64_t n, const double *V)
{
    BULK_PROLOGUE
    for (int64_t k = 0; k < n; k++) {
        double *v = (double *)(states[k] + L.vel);
        v[0] = V[2 * k], v[1] = 0.0, v[2] = V[2 * k + 1];
    }
    return 0;
}

/* out[k] = y component of angVel of body ids[k] */
int64_t yb_get_angvel_y(const int64_t *ids, int64_t n, double *out)
{
    BULK_PROLOGUE
    for (int64_t k = 0; k < n; k++) out[k] = ((const double *)(states[k] + L.angvel))[1];
    return 0;
}

/* O.forces.addT(ids[k], (0, T[k], 0)) */
int64_t yb_add_torque_y(const int64_t *ids, int64_t n, const double *T)
{
    BULK_PROLOGUE
    void *fc = c.scene + L.forces;
    for (int64_t k = 0; k < n; k++) {
        const double t[3] = {0.0, T[k], 0.0};
        Y.add_torque(fc, (int)ids[k], t);
    }
    return 0;
}

/* fn(forces, ids[k], (F[k,0], 0, F[k,1])) for every k */
static int64_t apply_xz(force_fn fn, const int64_t *ids, int64_t n, const double *F)
{
    BULK_PROLOGUE
    void *fc = c.scene + L.forces;
    for (int64_t k = 0; k < n; k++) {
        const double f[3] = {F[2 * k], 0.0, F[2 * k + 1]};
        fn(fc, (int)ids[k], f);
    }
    return 0;
}

/* O.forces.addF(ids[k], (F[k,0], 0, F[k,1])) */
int64_t yb_add_force_xz(const int64_t *ids, int64_t n, const double *F) { return apply_xz(Y.add_force, ids, n, F); }

/* O.forces.setPermF(ids[k], (F[k,0], 0, F[k,1])) */
int64_t yb_set_perm_force_xz(const int64_t *ids, int64_t n, const double *F)
{
    return apply_xz(Y.set_perm_force, ids, n, F);
}

/* ForceContainer::addForceUnsynced(ids[k], (F[k,0], 0, F[k,1])): straight into the summed forces
 * that NewtonIntegrator reads, with no sync() pass over all bodies (the one that permanent forces
 * cost every step). For a scene whose ForceResetter runs after its NewtonIntegrator: the forces
 * of the next step are written between steps into a reset container. syncSizesOfContainers()
 * first, so that every body id has its slot (addForceUnsynced does not check). The ids are
 * checked against that range only, not looked up: an erased body's slot takes its force unread
 * (the compiled steps write the forces of bodies whose positions they read in the same step,
 * and that read refuses an erased body). With the summed forces' data pointer known
 * (L.force_data), the same additions are made there, component by component, without a call
 * per body (addForceUnsynced is `_force[id] += f`). */
int64_t yb_add_force_unsynced_xz(const int64_t *ids, int64_t n, const double *F)
{
    Ctx c;
    int64_t err = begin(&c, n);
    if (err) return err;
    for (int64_t k = 0; k < n; k++)
        if (ids[k] < 0 || ids[k] >= c.n_bodies) return k + 1;
    char *fc = c.scene + L.forces;
    Y.sync_sizes(fc);
    if (L.force_data >= 0) {
        double *sum = *(double **)(fc + L.force_data); /* read after the resize: it may have moved */
        for (int64_t k = 0; k < n; k++) {
            double *f = sum + 3 * ids[k];
            f[0] += F[2 * k], f[1] += 0.0, f[2] += F[2 * k + 1];
        }
        return 0;
    }
    for (int64_t k = 0; k < n; k++) {
        const double f[3] = {F[2 * k], 0.0, F[2 * k + 1]};
        Y.add_force_unsynced(fc, (int)ids[k], f);
    }
    return 0;
}
