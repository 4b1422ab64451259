/* The state layout of cd_data: views of each system's block of y, joint
 * coordinates, and the event log and names. Below kinematics, dynamics,
 * contact and the integrator: knows where things are, not what they do. */
#include "capdyn/data.h"

#include <math.h>
#include <string.h>

static const char *ev_names[CD_EV_NKINDS] = {
    "onset", "separation", "stick_slip", "slip_stick", "slip_turn", "geometry_failure",
    "limit_engage", "limit_release", "user", "schedule", "clutch"};
static const char *owner_names[CD_OWNER_NKINDS] = {"slot", "joint", "actuator", "user", "finger"};
static const char *mode_names[3] = {"open", "stick", "slip"};

const char *cd_event_kind_name(cd_event_kind k)
{ return (k >= 0 && k < CD_EV_NKINDS) ? ev_names[k] : "?"; }
const char *cd_owner_kind_name(cd_owner_kind k)
{ return (k >= 0 && k < CD_OWNER_NKINDS) ? owner_names[k] : "?"; }
const char *cd_slot_mode_name(cd_slot_mode mo)
{ return (mo >= 0 && mo <= CD_MODE_SLIP) ? mode_names[mo] : "?"; }

const cd_event *cd_data_event(const cd_data *d, long i)
{
    if (!d) return NULL;
    long held = d->ev_count < d->ev_cap ? d->ev_count : d->ev_cap;
    long first = d->ev_count - held;
    if (i < 0 || i >= held) return NULL;
    return &d->ev[(first + i) % d->ev_cap];
}

/* offsets of a system's parts inside y */
static void sys_layout(const cd_model *m, int s, int *pos, int *q, int *vel, int *qd)
{
    int a = m->sys_y_adr[s], nj = m->sys_nbody[s] - 1;
    if (m->sys_base_type[s] == CD_BASE_FREE) {
        *pos = a; *q = a + 7; *vel = a + 7 + nj; *qd = a + 7 + nj + 6;
    } else {
        *pos = -1; *q = a; *vel = -1; *qd = a + nj;
    }
}

cd_sys_state cd_state_of(const cd_model *m, const cd_data *d, int s)
{
    cd_sys_state r;
    int pos, q, vel, qd;
    if (!m || !d) {
        memset(&r, 0, sizeof r);
        return r;
    }
    sys_layout(m, s, &pos, &q, &vel, &qd);
    r.njoint = m->sys_nbody[s] - 1;
    r.pos = pos >= 0 ? d->y + pos : NULL;
    r.quat = pos >= 0 ? d->y + pos + 3 : NULL;
    r.vel = vel >= 0 ? d->y + vel : NULL;
    r.angvel = vel >= 0 ? d->y + vel + 3 : NULL;
    r.q = d->y + q;
    r.qd = d->y + qd;
    return r;
}

/* y index of body b's joint coordinate (qd: its rate), as sys_layout
 * places it; called per joint in every evaluation, so without the views */
static int joint_y(const cd_model *m, int b, int rate)
{
    int s = m->body_sys[b], a = m->sys_y_adr[s], nj = m->sys_nbody[s] - 1, j = b - m->sys_body_adr[s] - 1;
    int free_base = m->sys_base_type[s] == CD_BASE_FREE;
    return a + (free_base ? 7 : 0) + (rate ? nj + (free_base ? 6 : 0) : 0) + j;
}

double cd_joint_q(const cd_model *m, const cd_data *d, int b)
{
    if (!m || !d) return NAN;
    if (m->body_parent[b] < 0) return 0.0;
    return d->y[joint_y(m, b, 0)];
}

double cd_joint_qd(const cd_model *m, const cd_data *d, int b)
{
    if (!m || !d) return NAN;
    if (m->body_parent[b] < 0) return 0.0;
    return d->y[joint_y(m, b, 1)];
}

