/* The generic switch table: dispatch to each unit's provider. */
#include "switch.h"
#include "../contact/contact.h"
#include "../mechanism/actuation.h"

#include <string.h>

int cd_sw_skip(const cd_model *m, const cd_data *d, int u)
{
    if (u < m->nslot) return d->slot_geomfail[u];
    if (u >= m->nsw - m->nuser) return !d->user_switch || !d->user_transition;
    return 0;
}

void cd_sw_functions(const cd_model *m, const cd_data *d, int u, int forgive, double g[2])
{
    int i = u;
    if (i < m->nslot) { cd_contact_switch(m, d, i, forgive, g); return; }
    i -= m->nslot;
    if (i < m->nlim) { cd_limit_functions(m, d, i, g); return; }
    i -= m->nlim;
    if (i < m->nfric) { cd_fric_functions(m, d, i, forgive, g); return; }
    i -= m->nfric;
    if (i < m->nfinger) { cd_finger_functions(m, d, i, g); return; }
    i -= m->nfinger;
    g[0] = d->user_switch(m, d, i, d->switch_user);
    if (g[0] != g[0]) g[0] = 1.0; /* a NaN from a user function never fires */
    g[1] = 1.0;
}

int cd_sw_transition(const cd_model *m, cd_data *d, int u, int forgive, cd_event *ev)
{
    int i = u;
    memset(ev, 0, sizeof *ev);
    ev->slot = ev->body_a = ev->body_b = -1;
    if (i < m->nslot) return cd_contact_transition(m, d, i, forgive, ev);
    i -= m->nslot;
    if (i < m->nlim) return cd_limit_transition(m, d, i, ev);
    i -= m->nlim;
    if (i < m->nfric) return cd_fric_transition(m, d, i, ev);
    i -= m->nfric;
    if (i < m->nfinger) return cd_finger_transition(m, d, i, ev);
    i -= m->nfinger;
    {
        double g[2];
        int from = d->user_mode[i];
        cd_sw_functions(m, d, u, forgive, g);
        if (!(g[0] < 0)) return 0;
        d->user_mode[i] = d->user_transition(m, d, i, d->switch_user);
        ev->kind = CD_EV_USER;
        ev->owner_kind = CD_OWNER_USER;
        ev->owner = i;
        ev->mode_from = from;
        ev->mode_to = d->user_mode[i];
        return 1;
    }
}
