/* capdyn: URDF import (include/capdyn/io.h, docs/urdf.md).
 *
 * Parsing is Debian's liburdfdom (urdf::parseURDF). urdfdom gives no line
 * numbers and reports its errors through console_bridge (a process-wide
 * output handler), so:
 *   - a small scanner of the XML text (comments blanked) finds the line of
 *     every <link> and <joint> by its name attribute, and each joint's
 *     <parent>/<child>; the tree checks (unknown link, second parent = a
 *     loop, cycle, several roots) run on that scan BEFORE urdfdom, with the
 *     element and its line in the message;
 *   - urdfdom then parses; its console_bridge messages are captured (under a
 *     mutex, the handler is global) and the first error becomes ours.
 * The tree is flattened into capdyn bodies: a fixed joint merges its child's
 * mass, CoM, inertia (parallel-axis theorem), collision shapes and child
 * joints into the moving ancestor. The root body's frame is moved to its CoM
 * (capdyn's base frame origin is the base CoM, docs/dynamics.md).
 * Meshes (STL ascii/binary, OBJ) become convex hulls (Qhull). */
#include "capdyn/io.h"
#include "capdyn/build.h"
#include "../math/cd_math.h"

#include <urdf_parser/urdf_parser.h>
#include <console_bridge/console.h>
extern "C" {
#include <libqhull_r/qhull_ra.h>
}

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <new>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct UrdfError {
    cd_status st;
    std::string msg;
};

[[noreturn]] void fail(const std::string &m, cd_status st = CD_EINVAL) { throw UrdfError{st, m}; }

struct UShape {
    int type;
    std::string name;  /* the <collision name>, else LINK or LINK_N (N from 1 when a link has several) */
    std::string what;  /* "link 'x' <collision> 2 (line N)" */
    double pos[3], rot[9], size[3], radius, length;
    std::vector<double> verts;
};

struct UBody {
    std::string link, joint;   /* joint: empty for the root */
    int parent = -1;           /* index into bodies */
    int jtype = 0;             /* cd_joint_type */
    bool continuous = false;
    double pos[3] = {0, 0, 0}, rot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, axis[3] = {0, 0, 1};
    double mass = 0, com[3] = {0, 0, 0}, I[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}; /* about com, body frame */
    bool limited = false;
    double lower = 0, upper = 0, damping = 0, friction = 0;
    std::vector<UShape> shapes;
    std::vector<std::array<double, 3>> ends; /* child joint origins (check point segments) */
    std::vector<std::string> merged;          /* links merged through fixed joints */
    int line = 0, jline = 0;
};

struct ScanJoint {
    std::string name, parent, child;
    int line = 0;
};

}  // namespace

struct cd_urdf {
    std::string path, robot, warnings;
    std::vector<UBody> bodies;
    std::map<std::string, int> joint_body;  /* joint name -> body index, -1 for a fixed joint */
    std::map<std::string, int> joint_line;
    std::vector<std::string> shape_names; /* in build order */
};

namespace {

/* ---- the XML scan (lines) ---------------------------------------------------- */

int line_at(const std::string &t, size_t pos)
{
    int n = 1;
    for (size_t i = 0; i < pos && i < t.size(); i++)
        if (t[i] == '\n') n++;
    return n;
}

/* blank out <!-- --> comments, keeping newlines (lines stay right) */
std::string blank_comments(std::string t)
{
    size_t p = 0;
    while ((p = t.find("<!--", p)) != std::string::npos) {
        size_t e = t.find("-->", p + 4);
        e = e == std::string::npos ? t.size() : e + 3;
        for (size_t i = p; i < e; i++)
            if (t[i] != '\n') t[i] = ' ';
        p = e;
    }
    return t;
}

/* attribute `a` of the tag starting at p ("<tag ...>"), "" if none */
std::string attr(const std::string &t, size_t p, const std::string &a)
{
    size_t e = t.find('>', p);
    if (e == std::string::npos) e = t.size();
    std::string tag = t.substr(p, e - p);
    size_t k = 0;
    while ((k = tag.find(a, k)) != std::string::npos) {
        bool start = k > 0 && std::isspace((unsigned char)tag[k - 1]);
        size_t j = k + a.size();
        while (j < tag.size() && std::isspace((unsigned char)tag[j])) j++;
        if (start && j < tag.size() && tag[j] == '=') {
            j++;
            while (j < tag.size() && std::isspace((unsigned char)tag[j])) j++;
            if (j < tag.size() && (tag[j] == '"' || tag[j] == '\'')) {
                size_t q = tag.find(tag[j], j + 1);
                if (q != std::string::npos) return tag.substr(j + 1, q - j - 1);
            }
        }
        k = j;
    }
    return "";
}

/* positions of the tags <name (followed by a space, '>' or '/') */
std::vector<size_t> tags(const std::string &t, const std::string &name, size_t from = 0, size_t to = std::string::npos)
{
    std::vector<size_t> v;
    std::string open = "<" + name;
    size_t p = from;
    while ((p = t.find(open, p)) != std::string::npos && p < to) {
        char c = p + open.size() < t.size() ? t[p + open.size()] : '>';
        if (std::isspace((unsigned char)c) || c == '>' || c == '/') v.push_back(p);
        p += open.size();
    }
    return v;
}

/* ---- small linear algebra ------------------------------------------------------ */

void rot_of(const urdf::Rotation &r, double R[9])
{
    double q[4] = {r.w, r.x, r.y, r.z};
    cd_quat_to_m3(R, q);
}

void pose_of(const urdf::Pose &p, double pos[3], double R[9])
{
    pos[0] = p.position.x;
    pos[1] = p.position.y;
    pos[2] = p.position.z;
    rot_of(p.rotation, R);
}

/* A = R B R^T */
void rotate_inertia(const double R[9], const double B[9], double A[9])
{
    double T[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0;
            for (int k = 0; k < 3; k++) s += R[3 * i + k] * B[3 * k + j];
            T[3 * i + j] = s;
        }
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0;
            for (int k = 0; k < 3; k++) s += T[3 * i + k] * R[3 * j + k];
            A[3 * i + j] = s;
        }
}

/* positive definite by Cholesky (leading minors) */
bool pos_def(const double I[9])
{
    double a = I[0], b = I[1], c = I[2], e = I[4], f = I[5], i = I[8];
    double m2 = a * e - b * b;
    double m3 = a * (e * i - f * f) - b * (b * i - f * c) + c * (b * f - e * c);
    return a > 0 && m2 > 0 && m3 > 0 && std::isfinite(m3);
}

/* adds mass m2 with CoM c2 and inertia I2 (about c2), all in b's frame */
void merge_mass(UBody &b, double m2, const double c2[3], const double I2[9])
{
    double m = b.mass + m2, c[3], Io[9];
    if (!(m > 0)) return;
    for (int k = 0; k < 3; k++) c[k] = (b.mass * b.com[k] + m2 * c2[k]) / m;
    for (int k = 0; k < 9; k++) Io[k] = b.I[k] + I2[k];
    const double *cs[2] = {b.com, c2};
    double ms[2] = {b.mass, m2};
    for (int s = 0; s < 2; s++) {
        double d[3] = {cs[s][0] - c[0], cs[s][1] - c[1], cs[s][2] - c[2]};
        double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) Io[3 * i + j] += ms[s] * ((i == j ? dd : 0.0) - d[i] * d[j]);
    }
    b.mass = m;
    std::memcpy(b.com, c, sizeof c);
    std::memcpy(b.I, Io, sizeof Io);
}

/* ---- meshes ------------------------------------------------------------------- */

/* STL (ascii or binary) or OBJ vertices, scaled; fails with a message naming the file */
std::vector<double> read_mesh(const std::string &file, const std::string &what, const double scale[3])
{
    std::string ext = std::filesystem::path(file).extension().string();
    for (char &ch : ext) ch = (char)std::tolower((unsigned char)ch);
    if (ext != ".obj" && ext != ".stl")
        fail(what + ": mesh '" + file + "': expected an .stl (ascii or binary) or .obj file (other formats: convert the mesh)");
    std::ifstream in(file, std::ios::binary);
    if (!in) fail(what + ": cannot read mesh file '" + file + "': " + std::strerror(errno), CD_EIO);
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec)) fail(what + ": mesh file '" + file + "' is not a regular file", CD_EIO);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<double> v;
    if (ext == ".obj") {
        std::istringstream s(data);
        std::string l;
        while (std::getline(s, l)) {
            std::istringstream ls(l);
            std::string k;
            double x, y, z;
            if ((ls >> k) && k == "v") {
                if (!(ls >> x >> y >> z)) fail(what + ": mesh '" + file + "': a 'v' line without three numbers");
                v.insert(v.end(), {x, y, z});
            }
        }
    } else if (ext == ".stl") {
        bool binary = false;
        if (data.size() >= 84) {
            uint32_t nt;
            std::memcpy(&nt, data.data() + 80, 4);
            binary = data.size() == 84 + 50 * (size_t)nt;
        }
        if (binary) {
            uint32_t nt;
            std::memcpy(&nt, data.data() + 80, 4);
            for (uint32_t t = 0; t < nt; t++)
                for (int k = 0; k < 3; k++) {
                    float f[3];
                    std::memcpy(f, data.data() + 84 + 50 * (size_t)t + 12 + 12 * k, 12);
                    v.insert(v.end(), {(double)f[0], (double)f[1], (double)f[2]});
                }
        } else {
            std::istringstream s(data);
            std::string w;
            while (s >> w)
                if (w == "vertex") {
                    double x, y, z;
                    if (!(s >> x >> y >> z)) fail(what + ": mesh '" + file + "': a 'vertex' without three numbers");
                    v.insert(v.end(), {x, y, z});
                }
        }
    } else {
        fail(what + ": mesh '" + file + "': expected an .stl (ascii or binary) or .obj file");
    }
    for (size_t i = 0; i < v.size(); i++) {
        v[i] *= scale[i % 3];
        if (!std::isfinite(v[i])) fail(what + ": mesh '" + file + "': a vertex coordinate is not finite");
    }
    if (v.size() < 12) fail(what + ": mesh '" + file + "': expected at least 4 vertices, got " + std::to_string(v.size() / 3));
    return v;
}

/* The convex hull's vertices (Qhull); *outside: mesh vertices farther than a
 * round-off tolerance inside the hull (the mesh is then not convex). */
std::vector<double> hull(const std::vector<double> &pts, const std::string &what, int *inside)
{
    qhT qh_qh;
    qhT *qh = &qh_qh;
    char *errtext = nullptr;
    size_t errlen = 0;
    FILE *ferr = open_memstream(&errtext, &errlen);
    if (!ferr) fail(what + ": cannot open a stream for Qhull's messages", CD_ENOMEM);
    std::vector<double> p = pts, out;
    int n = (int)(pts.size() / 3), curlong, totlong;
    double ext = 0;
    for (double x : pts) ext = std::fmax(ext, std::fabs(x));
    qh_zero(qh, ferr);
    int code = qh_new_qhull(qh, 3, n, p.data(), False, (char *)"qhull Qt", nullptr, ferr);
    *inside = 0;
    if (code == qh_ERRnone) {
        vertexT *vertex;
        facetT *facet;
        FORALLvertices out.insert(out.end(), {vertex->point[0], vertex->point[1], vertex->point[2]});
        double tol = std::fmax(qh->DISTround, 1e-9 * ext);
        for (int i = 0; i < n; i++) {
            double dmax = -HUGE_VAL;
            FORALLfacets {
                double d = facet->offset;
                for (int k = 0; k < 3; k++) d += facet->normal[k] * pts[3 * i + k];
                dmax = std::fmax(dmax, d);
            }
            if (dmax < -tol) (*inside)++;
        }
    }
    qh_freeqhull(qh, !qh_ALL);
    qh_memfreeshort(qh, &curlong, &totlong);
    std::fclose(ferr);
    std::string msg = errtext ? errtext : "";
    std::free(errtext);
    if (code != qh_ERRnone) {
        size_t nl = msg.find('\n');
        fail(what + ": the mesh's convex hull failed (Qhull exit " + std::to_string(code) +
             (code == qh_ERRsingular ? ": the mesh is flat or degenerate" : "") + ")" +
             (msg.empty() ? "" : ": " + msg.substr(0, nl)));
    }
    return out;
}

/* ---- urdfdom with its messages captured ------------------------------------------ */

struct Capture : console_bridge::OutputHandler {
    std::string first;
    void log(const std::string &text, console_bridge::LogLevel level, const char *, int) override
    {
        if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR && first.empty()) first = text;
    }
};

std::mutex urdfdom_mutex;

std::string fmt(double v)
{
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v);
    return b;
}

cd_urdf *read_urdf(const char *path)
{
    if (!path) fail("cd_urdf_read: the path is NULL");
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(std::string(path) + ": cannot read the URDF file: " + std::strerror(errno), CD_EIO);
    {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(path, ec)) fail(std::string(path) + ": the URDF path is not a regular file", CD_EIO);
    }
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::string P = path;
    std::unique_ptr<cd_urdf> u(new cd_urdf);
    u->path = P;
    std::string t = blank_comments(text);

    /* scan links and joints: names, lines, parents, children */
    std::map<std::string, int> link_line;
    for (size_t p : tags(t, "link")) {
        std::string n = attr(t, p, "name");
        int ln = line_at(t, p);
        if (n.empty()) fail(P + ":" + std::to_string(ln) + ": <link> without a name attribute");
        if (link_line.count(n))
            fail(P + ":" + std::to_string(ln) + ": <link name=\"" + n + "\">: a second link of that name (the first is at line " +
                 std::to_string(link_line[n]) + ")");
        link_line[n] = ln;
    }
    std::vector<ScanJoint> joints;
    std::vector<size_t> jt = tags(t, "joint");
    for (size_t i = 0; i < jt.size(); i++) {
        ScanJoint j;
        j.line = line_at(t, jt[i]);
        j.name = attr(t, jt[i], "name");
        std::string where = P + ":" + std::to_string(j.line) + ": <joint name=\"" + j.name + "\">";
        if (j.name.empty()) fail(P + ":" + std::to_string(j.line) + ": <joint> without a name attribute");
        if (u->joint_line.count(j.name))
            fail(where + ": a second joint of that name (the first is at line " + std::to_string(u->joint_line[j.name]) + ")");
        u->joint_line[j.name] = j.line;
        size_t end = t.find("</joint>", jt[i]);
        size_t next = i + 1 < jt.size() ? jt[i + 1] : t.size();
        if (end == std::string::npos || end > next) end = next;
        std::string type = attr(t, jt[i], "type");
        if (type == "floating" || type == "planar")
            fail(where + ": type '" + type + "' is refused (capdyn imports revolute, continuous, prismatic and fixed "
                 "joints; a free root is [[system]] base = \"free\")");
        if (!tags(t, "mimic", jt[i], end).empty())
            fail(where + ": <mimic> is refused (a joint coupled to another; capdyn joints are independent: couple them "
                 "with an actuator's transmission instead)");
        auto pa = tags(t, "parent", jt[i], end), ch = tags(t, "child", jt[i], end);
        if (pa.empty()) fail(where + ": no <parent link=\"...\"/>");
        if (ch.empty()) fail(where + ": no <child link=\"...\"/>");
        j.parent = attr(t, pa[0], "link");
        j.child = attr(t, ch[0], "link");
        if (!link_line.count(j.parent))
            fail(where + ": parent link '" + j.parent + "' is not a <link> of the file");
        if (!link_line.count(j.child))
            fail(where + ": child link '" + j.child + "' is not a <link> of the file");
        joints.push_back(j);
    }
    if (link_line.empty()) fail(P + ": no <link> in the file");
    /* a tree: one parent per link, one root, every link reachable */
    std::map<std::string, const ScanJoint *> parent_of;
    std::map<std::string, std::vector<std::string>> children;
    for (const ScanJoint &j : joints) {
        if (parent_of.count(j.child)) {
            const ScanJoint *o = parent_of[j.child];
            fail(P + ":" + std::to_string(j.line) + ": <joint name=\"" + j.name + "\">: link '" + j.child +
                 "' already has the parent joint '" + o->name + "' (line " + std::to_string(o->line) +
                 "): a kinematic loop, refused (a capdyn system is a tree)");
        }
        parent_of[j.child] = &j;
        children[j.parent].push_back(j.child);
    }
    std::vector<std::string> roots;
    for (auto &l : link_line)
        if (!parent_of.count(l.first)) roots.push_back(l.first);
    if (roots.empty()) {
        const ScanJoint &j = joints.front();
        fail(P + ":" + std::to_string(j.line) + ": <joint name=\"" + j.name +
             "\">: the joints form a cycle (no link is without a parent joint, so there is no root link)");
    }
    if (roots.size() > 1)
        fail(P + ":" + std::to_string(link_line[roots[1]]) + ": <link name=\"" + roots[1] + "\">: a second root link (besides '" +
             roots[0] + "', line " + std::to_string(link_line[roots[0]]) + "): expected one tree (every other link a child of a joint)");
    {
        std::set<std::string> seen;
        std::vector<std::string> st = {roots[0]};
        while (!st.empty()) {
            std::string l = st.back();
            st.pop_back();
            seen.insert(l);
            for (auto &c : children[l]) st.push_back(c);
        }
        for (const ScanJoint &j : joints)
            if (!seen.count(j.child))
                fail(P + ":" + std::to_string(j.line) + ": <joint name=\"" + j.name + "\">: link '" + j.child +
                     "' is on a cycle of joints, unreachable from the root link '" + roots[0] + "'");
    }

    /* parse with urdfdom, its messages captured */
    urdf::ModelInterfaceSharedPtr model;
    {
        std::lock_guard<std::mutex> lock(urdfdom_mutex);
        Capture cap;
        console_bridge::useOutputHandler(&cap);
        try {
            model = urdf::parseURDF(text);
        } catch (const std::exception &e) {
            if (cap.first.empty()) cap.first = e.what();
        }
        console_bridge::restorePreviousOutputHandler();
        /* an error urdfdom logged but recovered from (a value it could not
         * read, the element then dropped) is an error here too */
        if (!cap.first.empty()) model.reset();
        if (!model) {
            /* urdfdom names the element as "[name]": give its line */
            std::string where = P;
            for (auto &j : u->joint_line)
                if (cap.first.find("[" + j.first + "]") != std::string::npos) where = P + ":" + std::to_string(j.second) + ": <joint name=\"" + j.first + "\">";
            for (auto &l : link_line)
                if (where == P && cap.first.find("[" + l.first + "]") != std::string::npos) where = P + ":" + std::to_string(l.second) + ": <link name=\"" + l.first + "\">";
            if (where == P) {
                /* else the line of the first attribute value it quotes, "[value]" */
                size_t a = cap.first.find('['), b = a == std::string::npos ? a : cap.first.find(']', a);
                if (b != std::string::npos && b > a + 1) {
                    std::string v = cap.first.substr(a + 1, b - a - 1);
                    size_t at = t.find("\"" + v + "\"");
                    if (at == std::string::npos) at = t.find("'" + v + "'");
                    if (at != std::string::npos) where = P + ":" + std::to_string(line_at(t, at));
                }
            }
            fail(where + ": URDF parse error (urdfdom): " + (cap.first.empty() ? "no message" : cap.first));
        }
    }
    u->robot = model->getName();
    auto lline = [&](const std::string &l) { return P + ":" + std::to_string(link_line[l]) + ": <link name=\"" + l + "\">"; };
    auto jline = [&](const std::string &j) { return P + ":" + std::to_string(u->joint_line[j]) + ": <joint name=\"" + j + "\">"; };
    std::filesystem::path dir = std::filesystem::path(P).parent_path();

    /* depth first from the root, children in file order (urdfdom's order) */
    struct Item { urdf::LinkConstSharedPtr link; int host; double pos[3], rot[9]; /* link frame in host frame */ };
    std::vector<Item> stack;
    {
        Item r;
        r.link = model->getRoot();
        r.host = -1;
        std::memset(r.pos, 0, sizeof r.pos);
        cd_m3_identity(r.rot);
        stack.push_back(r);
    }
    while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        const urdf::Link &L = *it.link;
        int host = it.host;
        urdf::JointConstSharedPtr J = L.parent_joint;
        bool moving = !J || J->type != urdf::Joint::FIXED;
        double P0[3], R0[9];  /* this link's frame in the host's frame */
        std::memcpy(P0, it.pos, sizeof P0);
        std::memcpy(R0, it.rot, sizeof R0);
        if (moving) {
            UBody b;
            b.link = L.name;
            b.parent = host;
            b.line = link_line[L.name];
            if (J) {
                b.joint = J->name;
                b.jline = u->joint_line[J->name];
                double jp[3], jr[9];
                pose_of(J->parent_to_joint_origin_transform, jp, jr);
                /* joint frame in the host: host <- (P0,R0) parent link <- (jp,jr) */
                double tmp[3];
                cd_m3_mulv(tmp, R0, jp);
                for (int k = 0; k < 3; k++) b.pos[k] = P0[k] + tmp[k];
                cd_m3_mul(b.rot, R0, jr);
                b.axis[0] = J->axis.x;
                b.axis[1] = J->axis.y;
                b.axis[2] = J->axis.z;
                if (!(std::sqrt(b.axis[0] * b.axis[0] + b.axis[1] * b.axis[1] + b.axis[2] * b.axis[2]) > 1e-12))
                    fail(jline(J->name) + ": expected a non-zero <axis>");
                b.jtype = J->type == urdf::Joint::PRISMATIC ? CD_JOINT_PRISMATIC : CD_JOINT_REVOLUTE;
                b.continuous = J->type == urdf::Joint::CONTINUOUS;
                if (J->type != urdf::Joint::REVOLUTE && J->type != urdf::Joint::CONTINUOUS && J->type != urdf::Joint::PRISMATIC)
                    fail(jline(J->name) + ": unsupported joint type (expected revolute, continuous, prismatic or fixed)");
                if (J->limits && J->type != urdf::Joint::CONTINUOUS) {
                    if (!(J->limits->lower < J->limits->upper))
                        fail(jline(J->name) + ": <limit> expected lower < upper, got lower = " + fmt(J->limits->lower) +
                             ", upper = " + fmt(J->limits->upper));
                    b.limited = true;
                    b.lower = J->limits->lower;
                    b.upper = J->limits->upper;
                }
                if (J->dynamics) {
                    if (!(J->dynamics->damping >= 0)) fail(jline(J->name) + ": <dynamics> expected damping >= 0, got " + fmt(J->dynamics->damping));
                    b.damping = J->dynamics->damping;
                    b.friction = J->dynamics->friction;
                }
                u->joint_body[J->name] = (int)u->bodies.size();
            }
            host = (int)u->bodies.size();
            u->bodies.push_back(b);
            std::memset(P0, 0, sizeof P0);
            cd_m3_identity(R0);
        } else {
            u->joint_body[J->name] = -1;
            u->bodies[host].merged.push_back(L.name);
            /* the child joint's origin is a point of the host's segment */
        }
        UBody &H = u->bodies[host];
        if (!moving) H.ends.push_back({P0[0], P0[1], P0[2]});
        /* inertia */
        if (L.inertial) {
            const urdf::Inertial &in = *L.inertial;
            if (!(in.mass >= 0) || !std::isfinite(in.mass)) fail(lline(L.name) + ": <inertial> <mass value> expected >= 0, got " + fmt(in.mass));
            double Ii[9] = {in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz};
            if (in.mass > 0 && !pos_def(Ii))
                fail(lline(L.name) + ": <inertial> <inertia> expected a positive-definite matrix, got ixx = " + fmt(in.ixx) +
                     ", iyy = " + fmt(in.iyy) + ", izz = " + fmt(in.izz) + ", ixy = " + fmt(in.ixy) + ", ixz = " + fmt(in.ixz) +
                     ", iyz = " + fmt(in.iyz));
            double cp[3], cr[9], c[3], Rl[9], Il[9], tmp[3];
            pose_of(in.origin, cp, cr);
            cd_m3_mul(Rl, R0, cr);
            rotate_inertia(Rl, Ii, Il);
            cd_m3_mulv(tmp, R0, cp);
            for (int k = 0; k < 3; k++) c[k] = P0[k] + tmp[k];
            merge_mass(H, in.mass, c, Il);
        }
        /* collisions */
        int ci = 0;
        for (const auto &col : L.collision_array) {
            if (!col || !col->geometry) continue;
            ci++;
            UShape s;
            s.what = lline(L.name) + ": <collision> " + std::to_string(ci);
            s.name = !col->name.empty() ? col->name : L.collision_array.size() > 1 ? L.name + "_" + std::to_string(ci) : L.name;
            double cp[3], cr[9], tmp[3];
            pose_of(col->origin, cp, cr);
            cd_m3_mul(s.rot, R0, cr);
            cd_m3_mulv(tmp, R0, cp);
            for (int k = 0; k < 3; k++) s.pos[k] = P0[k] + tmp[k];
            s.radius = s.length = 0;
            s.size[0] = s.size[1] = s.size[2] = 0;
            const urdf::Geometry &g = *col->geometry;
            if (g.type == urdf::Geometry::SPHERE) {
                s.type = CD_SHAPE_SPHERE;
                s.radius = static_cast<const urdf::Sphere &>(g).radius;
                if (!(s.radius > 0)) fail(s.what + ": <sphere> expected radius > 0, got " + fmt(s.radius));
            } else if (g.type == urdf::Geometry::BOX) {
                const urdf::Box &bx = static_cast<const urdf::Box &>(g);
                s.type = CD_SHAPE_BOX;
                s.size[0] = bx.dim.x;
                s.size[1] = bx.dim.y;
                s.size[2] = bx.dim.z;
                for (double v : s.size)
                    if (!(v > 0)) fail(s.what + ": <box> expected positive sizes, got " + fmt(bx.dim.x) + " " + fmt(bx.dim.y) + " " + fmt(bx.dim.z));
            } else if (g.type == urdf::Geometry::CYLINDER) {
                const urdf::Cylinder &cy = static_cast<const urdf::Cylinder &>(g);
                s.type = CD_SHAPE_CYLINDER;
                s.radius = cy.radius;
                s.length = cy.length;
                if (!(s.radius > 0 && s.length > 0))
                    fail(s.what + ": <cylinder> expected radius > 0 and length > 0, got " + fmt(cy.radius) + ", " + fmt(cy.length));
            } else {
                const urdf::Mesh &me = static_cast<const urdf::Mesh &>(g);
                std::string f = me.filename;
                if (f.rfind("package://", 0) == 0)
                    fail(s.what + ": <mesh filename=\"" + f + "\">: package:// paths are not resolved (no ROS); give a path relative to the URDF file");
                if (f.rfind("file://", 0) == 0) f = f.substr(7);
                std::filesystem::path fp(f);
                if (fp.is_relative()) fp = dir / fp;
                double sc[3] = {me.scale.x, me.scale.y, me.scale.z};
                std::vector<double> v = read_mesh(fp.string(), s.what, sc);
                int inside = 0;
                s.type = CD_SHAPE_CONVEX;
                s.verts = hull(v, s.what + ": mesh '" + fp.string() + "'", &inside);
                if (inside > 0)
                    u->warnings += s.what + ": mesh '" + f + "' is not convex (" + std::to_string(inside) + " of " +
                                   std::to_string(v.size() / 3) + " vertices inside its hull): replaced by its convex hull (" +
                                   std::to_string(s.verts.size() / 3) + " vertices)\n";
            }
            H.shapes.push_back(s);
        }
        /* children, pushed in reverse so that they come out in file order */
        for (size_t k = L.child_links.size(); k-- > 0;) {
            Item c;
            c.link = L.child_links[k];
            c.host = host;
            urdf::JointConstSharedPtr cj = c.link->parent_joint;
            if (cj->type == urdf::Joint::FIXED) {
                double jp[3], jr[9], tmp[3];
                pose_of(cj->parent_to_joint_origin_transform, jp, jr);
                cd_m3_mulv(tmp, R0, jp);
                for (int q = 0; q < 3; q++) c.pos[q] = P0[q] + tmp[q];
                cd_m3_mul(c.rot, R0, jr);
            } else {
                std::memcpy(c.pos, P0, sizeof P0);  /* the moving child composes its joint origin itself */
                std::memcpy(c.rot, R0, sizeof R0);
            }
            stack.push_back(c);
        }
    }
    /* shape names in build order, unique */
    {
        std::set<std::string> seen;
        for (const UBody &b : u->bodies)
            for (const UShape &sh : b.shapes) {
                if (!seen.insert(sh.name).second) fail(sh.what + ": a second collision named '" + sh.name + "' (give <collision name=\"...\"> unique names)");
                u->shape_names.push_back(sh.name);
            }
    }
    /* masses after merging; the segments of check points */
    for (size_t i = 0; i < u->bodies.size(); i++) {
        UBody &b = u->bodies[i];
        if (!(b.mass > 0))
            fail(lline(b.link) + ": no <inertial> with a positive mass (on this " + (b.parent < 0 ? "root" : "moving") +
                 " link or a link fixed to it); capdyn bodies need a mass > 0");
        if (!pos_def(b.I)) fail(lline(b.link) + ": the inertia (with the links fixed to it) is not positive definite");
        if (b.parent >= 0) u->bodies[b.parent].ends.push_back({b.pos[0], b.pos[1], b.pos[2]});
    }
    return u.release();
}

}  // namespace

/* ---- the C API -------------------------------------------------------------------- */

extern "C" cd_urdf_opts cd_urdf_opts_default(void)
{
    cd_urdf_opts o;
    std::memset(&o, 0, sizeof o);
    o.quat[0] = 1.0;
    return o;
}

extern "C" cd_urdf *cd_urdf_read(const char *path, cd_error *err)
{
    try {
        return read_urdf(path);
    } catch (const UrdfError &e) {
        cd_error_set(err, e.st, "%s", e.msg.c_str());
    } catch (const std::bad_alloc &) {
        cd_error_set(err, CD_ENOMEM, "%s: out of memory", path ? path : "URDF");
    } catch (const std::exception &e) {
        cd_error_set(err, CD_EINVAL, "%s: %s", path ? path : "URDF", e.what());
    }
    return nullptr;
}

extern "C" void cd_urdf_free(cd_urdf *u) { delete u; }

extern "C" const char *cd_urdf_warnings(const cd_urdf *u) { return u ? u->warnings.c_str() : nullptr; }
extern "C" const char *cd_urdf_robot_name(const cd_urdf *u) { return u ? u->robot.c_str() : nullptr; }

extern "C" int cd_urdf_njoint(const cd_urdf *u) { return u ? (int)u->joint_body.size() : 0; }

extern "C" int cd_urdf_nshape(const cd_urdf *u) { return u ? (int)u->shape_names.size() : 0; }

extern "C" const char *cd_urdf_shape_name(const cd_urdf *u, int k)
{
    return u && k >= 0 && k < (int)u->shape_names.size() ? u->shape_names[(size_t)k].c_str() : nullptr;
}

extern "C" int cd_urdf_joint_index(const cd_urdf *u, const char *joint)
{
    if (!u || !joint) return -1;
    auto it = u->joint_body.find(joint);
    if (it == u->joint_body.end()) return -1;
    return it->second < 0 ? -2 : it->second;
}

extern "C" int cd_urdf_joint_body(const cd_urdf *u, const cd_model *m, int sys, const char *joint)
{
    if (!u || !m || !joint || sys < 0 || sys >= m->nsys) return -1;
    int k = cd_urdf_joint_index(u, joint);
    return k < 0 ? k : m->sys_body_adr[sys] + k;
}

extern "C" int cd_urdf_build(const cd_urdf *u, cd_model *m, const cd_urdf_opts *o, cd_error *err)
{
    if (!u || !m || !o) {
        cd_error_set(err, CD_EINVAL, "cd_urdf_build: the %s is NULL", !u ? "URDF" : !m ? "model" : "options");
        return -1;
    }
    if (o->nq0 < 0 || (o->nq0 > 0 && (!o->q0_joint || !o->q0))) {
        cd_error_set(err, CD_EINVAL, "cd_urdf_build: q0_joint or q0 is NULL with nq0 = %d", o->nq0);
        return -1;
    }
    if (!(o->checkpoint_spacing >= 0) || !(o->checkpoint_radius >= 0)) {
        cd_error_set(err, CD_EINVAL, "%s: checkpoint_spacing and checkpoint_radius must be >= 0", u->path.c_str());
        return -1;
    }
    std::map<std::string, double> q0;
    for (int i = 0; i < o->nq0; i++) {
        auto it = u->joint_body.find(o->q0_joint[i] ? o->q0_joint[i] : "");
        if (it == u->joint_body.end() || it->second < 0) {
            cd_error_set(err, CD_EINVAL, "%s: q0 of '%s': not a moving joint of the URDF", u->path.c_str(),
                         o->q0_joint[i] ? o->q0_joint[i] : "(null)");
            return -1;
        }
        q0[o->q0_joint[i]] = o->q0[i];
    }
    const UBody &root = u->bodies[0];
    /* base: frame moved to the root's CoM, same orientation */
    cd_system_desc sd = cd_system_desc_default();
    std::string nm = o->name ? o->name : u->robot;
    sd.name = nm.c_str();
    sd.type = o->fixed ? CD_BASE_FIXED : CD_BASE_FREE;
    sd.mass = root.mass;
    std::memcpy(sd.inertia, root.I, sizeof sd.inertia);
    double q[4], R[9], c[3];
    std::memcpy(q, o->quat, sizeof q);
    if (!cd_quat_normalize(q)) {
        cd_error_set(err, CD_EINVAL, "%s: base quaternion is zero", u->path.c_str());
        return -1;
    }
    cd_quat_to_m3(R, q);
    cd_m3_mulv(c, R, root.com);
    for (int k = 0; k < 3; k++) sd.pos[k] = o->pos[k] + c[k];
    std::memcpy(sd.quat, q, sizeof q);
    std::memcpy(sd.vel, o->vel, sizeof sd.vel);
    std::memcpy(sd.angvel, o->angvel, sizeof sd.angvel);
    int sys = cd_model_add_system(m, &sd, err);
    if (sys < 0) return -1;
    int b0 = m->sys_body_adr[sys];
    for (size_t i = 0; i < u->bodies.size(); i++) {
        const UBody &b = u->bodies[i];
        const double *shift = i == 0 ? root.com : nullptr; /* root frame -> base CoM frame */
        int id = b0;
        if (i > 0) {
            cd_link_desc l = cd_link_desc_default();
            l.name = b.link.c_str();
            l.parent = b0 + b.parent;
            l.type = (cd_joint_type)b.jtype;
            for (int k = 0; k < 3; k++) l.pos[k] = b.pos[k] - (b.parent == 0 ? root.com[k] : 0.0);
            std::memcpy(l.rot, b.rot, sizeof l.rot);
            std::memcpy(l.axis, b.axis, sizeof l.axis);
            l.mass = b.mass;
            std::memcpy(l.com, b.com, sizeof l.com);
            std::memcpy(l.inertia, b.I, sizeof l.inertia);
            auto it = q0.find(b.joint);
            if (it != q0.end()) l.q0 = it->second;
            if (b.limited && !o->ignore_limits && (l.q0 < b.lower || l.q0 > b.upper)) {
                cd_error_set(err, CD_EINVAL, "%s:%d: <joint name=\"%s\">: initial position %g outside its <limit> [%g, %g]",
                             u->path.c_str(), b.jline, b.joint.c_str(), l.q0, b.lower, b.upper);
                return -1;
            }
            id = cd_model_add_link(m, sys, &l, err);
            if (id < 0) return -1;
            if ((b.limited && !o->ignore_limits) || b.damping > 0) {
                cd_joint_props p = cd_joint_props_default();
                p.limited = b.limited && !o->ignore_limits;
                p.lower = b.lower;
                p.upper = b.upper;
                p.damping = b.damping;
                if (cd_model_set_joint(m, id, &p, err) != CD_OK) return -1;
            }
        }
        for (const UShape &s : b.shapes) {
            double pos[3];
            for (int k = 0; k < 3; k++) pos[k] = s.pos[k] - (shift ? shift[k] : 0.0);
            cd_shape_desc d = cd_shape_desc_default();
            d.type = s.type;
            std::memcpy(d.pos, pos, sizeof pos);
            std::memcpy(d.rot, s.rot, sizeof d.rot);
            d.radius = s.radius;
            d.length = s.length;
            std::memcpy(d.size, s.size, sizeof d.size);
            d.verts = s.verts.empty() ? nullptr : s.verts.data();
            d.nvert = (int)(s.verts.size() / 3);
            if (cd_build_shape(m, id, &d, err) < 0)
                return -1;
        }
        /* check points along the link: from its joint to each child joint
         * (to twice its CoM for a link without children), every
         * checkpoint_spacing, both ends included */
        if (i > 0 && o->checkpoint_spacing > 0) {
            std::vector<std::array<double, 3>> ends = b.ends;
            if (ends.empty()) ends.push_back({2 * b.com[0], 2 * b.com[1], 2 * b.com[2]});
            bool first = true;
            for (auto &e : ends) {
                double len = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
                int n = (int)std::ceil(len / o->checkpoint_spacing - 1e-9);
                if (n < 1) n = 1;
                if (n > 100000) {
                    cd_error_set(err, CD_EINVAL, "%s: link '%s': checkpoint_spacing %g m gives %d check points on a %g m segment",
                                 u->path.c_str(), b.link.c_str(), o->checkpoint_spacing, n, len);
                    return -1;
                }
                for (int k = first ? 0 : 1; k <= n; k++) {
                    double p[3] = {e[0] * k / n, e[1] * k / n, e[2] * k / n};
                    if (cd_model_add_checkpoint(m, id, p, o->checkpoint_radius, err) < 0) return -1;
                }
                first = false;
            }
        }
    }
    return sys;
}

extern "C" char *cd_urdf_describe(const cd_urdf *u, const cd_model *m, int sys)
{
    if (!u || !m || sys < 0 || sys >= m->nsys) return nullptr;
    std::string s;
    char line[512];
    int b0 = m->sys_body_adr[sys];
    std::snprintf(line, sizeof line, "  system '%s' from URDF '%s' (robot '%s'): %zu bodies, %s base\n", m->sys_name[sys],
                  u->path.c_str(), u->robot.c_str(), u->bodies.size(), m->sys_base_type[sys] == CD_BASE_FIXED ? "fixed" : "free");
    s += line;
    for (size_t i = 0; i < u->bodies.size(); i++) {
        const UBody &b = u->bodies[i];
        int id = b0 + (int)i;
        std::string merged;
        for (auto &x : b.merged) merged += (merged.empty() ? " + fixed " : ", ") + x;
        if (i == 0) {
            std::snprintf(line, sizeof line, "    body %-16s base                               mass %g kg%s\n", b.link.c_str(), b.mass, merged.c_str());
        } else {
            const char *ty = b.jtype == CD_JOINT_PRISMATIC ? "prismatic" : b.continuous ? "continuous" : "revolute";
            char lim[96];
            if (m->body_lim_id[id] >= 0)
                std::snprintf(lim, sizeof lim, "limits [%g, %g] %s", m->body_limit[6 * id], m->body_limit[6 * id + 1],
                              b.jtype == CD_JOINT_PRISMATIC ? "m" : "rad");
            else
                std::snprintf(lim, sizeof lim, b.limited ? "limits ignored" : "no limits");
            std::snprintf(line, sizeof line, "    body %-16s joint %-18s %-10s <- %-14s mass %g kg, %s%s\n", b.link.c_str(),
                          b.joint.c_str(), ty, u->bodies[b.parent].link.c_str(), b.mass, lim, merged.c_str());
        }
        s += line;
    }
    char *out = (char *)std::malloc(s.size() + 1);
    if (out) std::memcpy(out, s.c_str(), s.size() + 1);
    return out;
}
