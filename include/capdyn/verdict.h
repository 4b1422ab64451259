/* capdyn: capture verdicts and figures of merit of a grasp or a capture run
 * (issue 8; docs/grippers.md). A monitor watches a run sample by sample and
 * decides, from the physics only (docs/capture.md, "Verdicts"):
 *   captured    the capture conditions hold: the object is enclosed by the
 *               hand (its centre of mass, or the centre of its grasp feature,
 *               inside the polygon of the palm face and the fingers in the
 *               fingers' plane when the fingers turn about parallel axes, else
 *               inside the convex hull of the finger bases, joints and tips),
 *               its velocity relative to the palm has decayed below v_max and
 *               w_max, the fingers have stopped (every hand joint rate below
 *               w_max: the grasp has settled, it is not still closing), and
 *               the set of its contacts has not changed for `dwell` seconds;
 *               AND its contacts with the hand are in force closure, grasp
 *               quality epsilon > 0 (cd_monitor_quality) at that moment: the
 *               hand can resist any small wrench on it;
 *   caged       the capture conditions hold but the hand's contacts are not
 *               in force closure (epsilon = 0): enclosed and at rest, not
 *               gripped (fingertips jammed tip to tip over it, two fingers of
 *               three touching it). Not final: it becomes captured if a later
 *               contact set, settled, is in force closure, escaped if the
 *               object leaves; a run that ends caged reports caged;
 *   escaped     its centre of mass left the hand's workspace (a sphere of
 *               radius `workspace` about the palm centre);
 *   unresolved  none of these, when the run ends.
 * It also keeps the figures of merit: time to capture, peak contact force,
 * peak joint torque of the hand, contacts at the end (stick / slip), the
 * final offset of the object from the palm centre. No printing; the only
 * allocation after cd_monitor_init is the grasp analysis (Qhull allocates
 * and frees its scratch) when the capture conditions first hold for a
 * settled contact set: once per contact set, never inside a step. */
#ifndef CAPDYN_VERDICT_H
#define CAPDYN_VERDICT_H

#include "capdyn/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The codes are stable (results files, sweep summaries, Python, the FMU):
 * 0 unresolved, 1 captured, 2 escaped, 3 caged. */
typedef enum {
    CD_VERDICT_UNRESOLVED = 0,
    CD_VERDICT_CAPTURED = 1,
    CD_VERDICT_ESCAPED = 2,
    CD_VERDICT_CAGED = 3
} cd_verdict;
/* "unresolved", "captured", "escaped", "caged" (static strings). */
const char *cd_verdict_name(cd_verdict v);

typedef struct {
    int hand;             /* system of the hand (its base is the palm) */
    int object;           /* system of the object (a free base) */
    double v_max;         /* [m/s] relative speed below which it is at rest, default 1e-3 */
    double w_max;         /* [rad/s] relative angular speed, default 0.05 */
    double dwell;         /* [s] the contact set must hold this long, default 0.2 */
    double workspace;     /* [m] escape radius about the palm centre; 0 = 1.5 x the larger of (the
                             hand's reach + the arm's stretched length to the palm, for a hand
                             mounted on an arm) and the object's initial distance, computed at init */
    int feature;          /* shape of the object that is to be grasped (a handrail's bar): its
                             centre is the point tested for enclosure; -1 = the object's CoM */
    int palm;             /* palm body: the fingers are its child links; -1 = the hand's base
                             (a gripper mounted on an arm: the link it is mounted on) */
    double palm_pos[3];   /* palm frame origin on the palm body, body frame [m], default 0 */
    double palm_rot[9];   /* palm frame -> palm body frame, default identity */
} cd_monitor_opts;

/* Defaults above, hand and object -1 (must be set). */
cd_monitor_opts cd_monitor_opts_default(void);

typedef struct {
    cd_monitor_opts opt;
    cd_verdict verdict;
    double t_capture;     /* [s] first time every capture condition held with force closure (NaN if never) */
    double t_escape;      /* [s] (NaN if never) */
    double peak_fn;       /* [N] peak fn at samples: the largest normal force on the object, any slot,
                             at the samples the monitor saw (not between them) */
    double peak_tau;      /* [N m] largest |joint torque| (actuator + passive) of the hand */
    int n_stick, n_slip;  /* object contacts at the end */
    double offset[3];     /* [m] object CoM - palm centre (the palm frame's origin) at the end, palm frame */
    double offset_norm;
    double point[3];      /* the point tested for enclosure (feature centre or CoM), palm frame, at the end [m] */
    int enclosed;         /* at the last sample */
    double v_rel, w_rel;  /* at the last sample */
    double qd_max;        /* largest hand joint rate at the last sample [rad/s | m/s] */
    double t_cage;        /* [s] first time the capture conditions held without force closure (NaN if never) */
    double epsilon;       /* grasp quality of the hand's contacts when the verdict was last judged
                             (captured or caged); NaN before, or if the analysis failed */
    /* private */
    double t_set;         /* since when the contact set is unchanged */
    unsigned long set_hash;
    double reach;
    double t_judged;      /* t_set of the contact set whose closure was last judged (NaN: none) */
} cd_monitor;

/* Prepares a monitor for a run of d (at its initial state). CD_EINVAL if the
 * hand or object is not a valid system, or the object has no free base. */
cd_status cd_monitor_init(cd_monitor *mo, const cd_model *m, const cd_data *d, const cd_monitor_opts *opt,
                          cd_error *err);
/* Looks at the current state (after an evaluation); call it at every
 * sample or accepted step. Captured and escaped, once reached, are kept;
 * caged may still become captured or escaped. */
void cd_monitor_update(cd_monitor *mo, const cd_model *m, const cd_data *d);

/* The Ferrari-Canny epsilon of the object's closed contacts with the hand
 * (both bodies of the slot: one of the object, one of the hand's system; a
 * fixture or another body does not grip for the hand) at the current
 * state (analysis.h): contact points and inward normals from the slots, mu
 * from each slot's law (mu_max), about the object's CoM; planar in the
 * fingers' plane when every finger turns about parallel axes, else 3-D.
 * *eps = 0 and *closure = 0 without force closure. Status of the analysis. */
cd_status cd_monitor_quality(const cd_monitor *mo, const cd_model *m, const cd_data *d, double *eps, int *closure,
                             cd_error *err);

#ifdef __cplusplus
}
#endif
#endif
