/* O.step() for compiled callers: yb_steps runs YADE's Scene::moveToNextTimeStep, the function
 * O.step() calls, n times on the current scene. C++ only to catch what YADE's engines throw (an
 * exception must not unwind through a numba frame): the message is kept for yb_error(). */
#include <cstdint>
#include <exception>

extern "C" {
typedef void (*scene_step_fn)(void *);
void *yb_scene(void);
int yb_ready(void);
scene_step_fn yb_scene_step(void);
void yb_set_error(const char *text);
int64_t yb_steps(const int64_t *unused_ids, int64_t n, double *unused);
}

#define YB_ENOTREADY (-1)
#define YB_ENOSCENE (-2)
#define YB_EBADN (-3)
#define YB_ETHREW (-4) /* an engine threw: yb_error() says what */

/* n steps (the bulk signature, so that numba callers use one call convention; ids and the array
 * are not used). 0, YB_ETHREW after a step that threw, or another negative YB_E* code. */
int64_t yb_steps(const int64_t *, int64_t n, double *)
{
    scene_step_fn step = yb_scene_step();
    if (!yb_ready() || !step) return YB_ENOTREADY;
    if (n < 0) return YB_EBADN;
    for (int64_t k = 0; k < n; k++) {
        void *scene = yb_scene(); /* again each step: an engine may have switched scenes */
        if (!scene) return YB_ENOSCENE;
        try {
            step(scene);
        } catch (const std::exception &e) {
            yb_set_error(e.what());
            return YB_ETHREW;
        } catch (...) {
            yb_set_error("an engine threw an exception that is not a std::exception");
            return YB_ETHREW;
        }
    }
    return 0;
}
