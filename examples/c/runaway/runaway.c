/* The paper's runaway skill in C: if the nearest obstacle is closer than
 * safe_distance, back away from it and turn away. The I/O structs come from
 * `situate gen c runaway.yaml` (c_runaway.h). It counts the cycles it ran away
 * from each switch on (activate) and says the count when switched off
 * (deactivate), as the Rust, C++ and Python versions do. */
#include <math.h>

#include "c_runaway.h"

#define SONARS 24

struct c_runaway_state {
    uint64_t ran; /* cycles it ran away since it was last switched on */
};

/* Switched on: counts afresh (the state lives across activations). */
situate_status c_runaway_activate(c_runaway_state* state, const c_runaway_params* params, situate_context* cx) {
    (void)params;
    (void)cx;
    state->ran = 0;
    return SITUATE_OK;
}

situate_status c_runaway_step(c_runaway_state* state, const c_runaway_inputs* in, c_runaway_outputs* out,
                              const c_runaway_params* params, situate_context* cx) {
    const double two_pi = 2.0 * 3.14159265358979323846;
    double r_min = (double)in->sonar.range[0];
    int k = 0;
    (void)cx;
    for (int i = 1; i < SONARS; i++) {
        double r = (double)in->sonar.range[i];
        if (r < r_min) { /* ties: the lowest index wins */
            r_min = r;
            k = i;
        }
    }
    if (r_min >= params->safe_distance) {
        return SITUATE_OK; /* nothing near: write nothing */
    }
    double a = k <= 12 ? k * two_pi / SONARS : k * two_pi / SONARS - two_pi;
    out->drive.v = -0.3 * cos(a) * (1.0 - r_min / params->safe_distance);
    out->drive.w = -1.0 * sin(a);
    out->has_drive = true;
    state->ran++;
    return SITUATE_OK;
}

/* Switched off: says how long it ran away while on. */
situate_status c_runaway_deactivate(c_runaway_state* state, const c_runaway_params* params, situate_context* cx) {
    (void)params;
    situate_print(cx, "switched off after running away %llu cycles", (unsigned long long)state->ran);
    return SITUATE_OK;
}

SITUATE_LIBRARY(SITUATE_SKILL_WITH(c_runaway, NULL, NULL, NULL, c_runaway__activate, c_runaway__deactivate))
