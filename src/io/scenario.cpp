/* capdyn scenario loader: TOML (toml++ 3.3) -> cd_model, behind the C API of
 * include/capdyn/io.h. The only C++ translation unit of capdyn.
 *
 * Pipeline (docs/scenario-format.md is the user-facing reference):
 *   1. read + parse each file with toml++, convert it into a small tree of our
 *      own (Node) that keeps the file:line:column of every key and value;
 *   2. resolve `include = [...]` recursively (relative to the including file,
 *      cycles detected), deep-merging: tables merge key by key, arrays of
 *      tables merge element by element by their `name`, everything else is
 *      replaced by the including file's value;
 *   3. apply the --set overrides on the merged tree (their values carry the
 *      override text as their "location");
 *   4. walk the tree against the schema (unknown keys are errors with a
 *      did-you-mean), validate every value and call the C builder of
 *      model.h. Every builder error is prefixed with the location of the
 *      table that caused it.
 *
 * Why our own tree rather than toml++'s: merging and overriding must keep the
 * source position of each value (the error of a value that came from an
 * included file names that file), and toml++ nodes do not carry their
 * region through copies in a way we can rely on; the tree is tiny.
 *
 * Nothing here prints or exits, and no exception crosses the C boundary:
 * errors are thrown internally as LoadError and turned into cd_error at the
 * two entry points, which also catch std::bad_alloc and anything else. */
#include "capdyn/io.h"
#include "capdyn/build.h"
#include "../math/cd_math.h"

#include <toml++/toml.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <new>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace {

/* ---- locations and the value tree ------------------------------------------ */

using Str = std::shared_ptr<const std::string>;

/* Where a value came from: a file position, or an override (--set text). */
struct Loc {
    Str file;
    int line = 0, col = 0;
    Str ovr;
    std::string str() const
    {
        if (ovr) return "--set '" + *ovr + "'";
        if (!file) return "<scenario>";
        return *file + ":" + std::to_string(line > 0 ? line : 1) + ":" + std::to_string(col > 0 ? col : 1);
    }
};

enum class NK { Table, Array, Int, Float, Bool, String, Other };

struct Node;
using NodeP = std::shared_ptr<Node>;
struct Entry {
    std::string key;
    Loc kloc;  /* where the key is written */
    NodeP val;
};
struct Node {
    NK kind = NK::Table;
    Loc loc;
    std::vector<Entry> tab;  /* NK::Table, in source order */
    std::vector<NodeP> arr;  /* NK::Array */
    long long ival = 0;
    double fval = 0;
    bool bval = false;
    std::string sval;        /* NK::String; NK::Other: the literal */
    std::string component;   /* a table made by --set 'KEY.x=V' for a KEY the file lacks: "x" */
    std::string component_of;/* and that KEY's path */
    Entry *find(const std::string &k)
    {
        for (auto &e : tab)
            if (e.key == k) return &e;
        return nullptr;
    }
};

struct LoadError {
    cd_status st;
    std::string msg;
};

/* "LOC: key 'PATH': WHAT" (the key part omitted when path is empty). */
[[noreturn]] void fail_at(const Loc &l, const std::string &path, const std::string &what,
                          cd_status st = CD_EINVAL)
{
    std::string m = l.str() + ": ";
    if (!path.empty()) m += "key '" + path + "': ";
    m += what;
    throw LoadError{st, m};
}

std::string fmt_num(double v)
{
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char b[64];
    std::snprintf(b, sizeof b, "%.15g", v);
    return b;
}

/* A short rendering of a value for "got ..." (arrays inline, cut at 80 chars). */
std::string render(const Node &n)
{
    switch (n.kind) {
    case NK::Int: return std::to_string(n.ival);
    case NK::Float: return fmt_num(n.fval);
    case NK::Bool: return n.bval ? "true" : "false";
    case NK::String: return "'" + n.sval + "'";
    case NK::Other: return "a date/time value";
    case NK::Table:
        if (!n.component.empty())
            return "only the component '." + n.component + "' (--set named a component of a key the file does not "
                   "have: set the whole array instead, --set '" + n.component_of + "=[x, y, z]')";
        return "a table";
    case NK::Array: {
        std::string s = "[";
        for (size_t i = 0; i < n.arr.size(); i++) {
            if (i) s += ", ";
            s += render(*n.arr[i]);
            if (s.size() > 80) return s.substr(0, 80) + "...]";
        }
        return s + "]";
    }
    }
    return "?";
}

std::string join(const std::string &path, const std::string &key) { return path.empty() ? key : path + "." + key; }
std::string idx(const std::string &path, size_t i) { return path + "[" + std::to_string(i) + "]"; }

/* ---- did-you-mean ------------------------------------------------------------ */

size_t edit_distance(const std::string &a, const std::string &b)
{
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); j++) prev[j] = j;
    for (size_t i = 1; i <= a.size(); i++) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); j++) {
            size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
        }
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

std::string lower(std::string s)
{
    for (auto &c : s) c = (char)std::tolower((unsigned char)c);
    return s;
}

/* The closest candidate if it is close enough (edit distance, case-blind, at
 * most max(2, len/3)), else "". */
std::string closest(const std::string &w, const std::vector<std::string> &cands)
{
    std::string best;
    size_t bd = (size_t)-1;
    for (const auto &c : cands) {
        size_t d = edit_distance(lower(w), lower(c));
        if (d < bd) { bd = d; best = c; }
    }
    size_t thr = std::max<size_t>(2, w.size() / 3);
    return bd <= thr ? best : std::string();
}

std::string list(const std::vector<std::string> &c)
{
    std::string s;
    for (size_t i = 0; i < c.size(); i++) s += (i ? ", " : "") + std::string("'") + c[i] + "'";
    return s;
}

/* " (did you mean 'x'?)" or " (expected one of: ...)" */
std::string hint(const std::string &w, const std::vector<std::string> &cands)
{
    std::string c = closest(w, cands);
    if (!c.empty()) return " (did you mean '" + c + "'?)";
    if (cands.empty()) return "";
    return " (expected one of: " + list(cands) + ")";
}

/* ---- toml++ -> Node ------------------------------------------------------------ */

Loc mkloc(const toml::source_region &r, const Str &file, const Loc &fallback)
{
    if (r.begin.line == 0) return fallback;
    Loc l;
    l.file = file;
    l.line = (int)r.begin.line;
    l.col = (int)r.begin.column;
    return l;
}

NodeP convert(const toml::node &n, const Str &file, const Loc &fallback)
{
    auto out = std::make_shared<Node>();
    out->loc = mkloc(n.source(), file, fallback);
    switch (n.type()) {
    case toml::node_type::table: {
        out->kind = NK::Table;
        for (auto &&kv : *n.as_table()) {
            Entry e;
            e.key = std::string(kv.first.str());
            e.kloc = mkloc(kv.first.source(), file, out->loc);
            e.val = convert(kv.second, file, e.kloc);
            out->tab.push_back(std::move(e));
        }
        /* toml++ sorts keys; restore the source order so that the first error
         * reported is the first one in the file */
        std::stable_sort(out->tab.begin(), out->tab.end(), [](const Entry &a, const Entry &b) {
            return a.kloc.line != b.kloc.line ? a.kloc.line < b.kloc.line : a.kloc.col < b.kloc.col;
        });
        break;
    }
    case toml::node_type::array:
        out->kind = NK::Array;
        for (auto &&el : *n.as_array()) out->arr.push_back(convert(el, file, out->loc));
        break;
    case toml::node_type::string:
        out->kind = NK::String;
        out->sval = n.as_string()->get();
        break;
    case toml::node_type::integer:
        out->kind = NK::Int;
        out->ival = (long long)n.as_integer()->get();
        break;
    case toml::node_type::floating_point:
        out->kind = NK::Float;
        out->fval = n.as_floating_point()->get();
        break;
    case toml::node_type::boolean:
        out->kind = NK::Bool;
        out->bval = n.as_boolean()->get();
        break;
    default:
        out->kind = NK::Other;
        out->sval = "date/time";
        break;
    }
    return out;
}

void set_loc_all(Node &n, const Loc &l)
{
    n.loc = l;
    for (auto &e : n.tab) {
        e.kloc = l;
        set_loc_all(*e.val, l);
    }
    for (auto &a : n.arr) set_loc_all(*a, l);
}

bool is_aot(const Node &n)
{
    if (n.kind != NK::Array || n.arr.empty()) return false;
    for (auto &a : n.arr)
        if (a->kind != NK::Table) return false;
    return true;
}

const std::string *name_of(Node &t)
{
    Entry *e = t.kind == NK::Table ? t.find("name") : nullptr;
    return (e && e->val->kind == NK::String) ? &e->val->sval : nullptr;
}

/* ---- includes -------------------------------------------------------------------- */

/* A copy of a tree that shares no node with it (merging mutates the base);
 * adds the number of nodes copied to *count. */
NodeP deep_copy(const Node &n, unsigned long long *count)
{
    auto c = std::make_shared<Node>(n);
    ++*count;
    for (auto &e : c->tab) e.val = deep_copy(*e.val, count);
    for (auto &a : c->arr) a = deep_copy(*a, count);
    return c;
}

/* Deep merge of `over` into `base` (over wins). Tables merge key by key; arrays
 * of tables merge element by element on `name` (a named element of `over`
 * updates the first element of `base` with that name, any other is appended);
 * every other value is replaced. Keys and names are looked up in hash maps:
 * a table of 10^5 keys or 10^5 named elements merges in linear time. */
void merge_into(Node &base, Node &over)
{
    std::unordered_map<std::string, size_t> at;
    for (size_t i = 0; i < base.tab.size(); i++) at.emplace(base.tab[i].key, i);
    for (auto &e : over.tab) {
        auto it = at.find(e.key);
        if (it == at.end()) {
            at.emplace(e.key, base.tab.size());
            base.tab.push_back(e);
            continue;
        }
        Entry *b = &base.tab[it->second];
        if (b->val->kind == NK::Table && e.val->kind == NK::Table) {
            merge_into(*b->val, *e.val);
        } else if (is_aot(*b->val) && is_aot(*e.val)) {
            std::unordered_map<std::string, size_t> named;
            auto &arr = b->val->arr;
            for (size_t j = 0; j < arr.size(); j++)
                if (const std::string *xn = name_of(*arr[j])) named.emplace(*xn, j);
            for (auto &o : e.val->arr) {
                const std::string *on = name_of(*o);
                auto hit = on ? named.find(*on) : named.end();
                if (hit != named.end()) {
                    merge_into(*arr[hit->second], *o);
                } else {
                    if (on) named.emplace(*on, arr.size());
                    arr.push_back(o);
                }
            }
        } else {
            *b = e;
        }
    }
}

/* The most samples a run may ask for: duration / output_dt <= 1e9. */
const double CD_SCENARIO_MAX_SAMPLES = 1e9;
/* The largest scenario file (main or included) the loader reads. */
const unsigned long long CD_SCENARIO_MAX_BYTES = 16ull << 20;

/* ---- input bounds (docs/scenario-format.md "Limits", docs/reliability.md) ----
 * Whatever the input, loading ends in bounded time and stack: the loader,
 * toml++ (3.3 has no depth limit for dotted keys and table headers; its
 * parser and its destructors recurse once per level) and our own tree walks
 * recurse once per nesting level, so the nesting is bounded before the text
 * reaches toml++; includes are bounded in depth and in total bytes, and a
 * file included twice is read and parsed once. Tested in
 * tests/test_loader_limits.c, at a 256 KiB stack. */
const int CD_MAX_INCLUDE_DEPTH = 32;                 /* nested include levels below the main file */
const unsigned long long CD_MAX_TOTAL_BYTES = 64ull << 20; /* the main file and all includes */
const int CD_MAX_KEY_NAMES = 32;                     /* names in one dotted key or table header */
const int CD_MAX_NESTING = 64;                       /* tables, dotted keys, arrays, inline tables together */
const size_t CD_MAX_HULL_VERTICES = 128;             /* the hull is built by an O(n^4) search */
const size_t CD_MAX_TOTAL_HULL_VERTICES = 2048;      /* all convex shapes together */
const unsigned long long CD_MAX_REUSED_VALUES = 10000000; /* values copied for files included again */

bool is_bare(char c) { return std::isalnum((unsigned char)c) || c == '_' || c == '-'; }

/* The light lexer that bounds what reaches toml++. It follows strings
 * (basic, literal, multi-line), comments, table headers, keys and the
 * [ { } ] of values, and measures each value's depth: the names of the
 * current table header, plus the names of the dotted key, plus one per
 * enclosing array or inline table. It does not validate anything else
 * (toml++ does, with its own messages). loc_of maps an offset to the
 * location reported. */
template <class LocOf> void prescan(const std::string &s, LocOf loc_of)
{
    struct Open { char c; int depth; };
    std::vector<Open> st;
    size_t i = 0, n = s.size();
    int table_depth = 0, val_depth = 0;
    bool expect_key = true;
    auto too_deep = [&](size_t at, int d) {
        if (d > CD_MAX_NESTING)
            fail_at(loc_of(at), "", "expected values nested at most " + std::to_string(CD_MAX_NESTING) +
                                        " levels deep (table header names, dotted key names, arrays and inline "
                                        "tables together), got deeper");
    };
    /* skips the string starting at s[i] (a quote); false if unterminated */
    auto skip_string = [&](size_t &j) -> bool {
        char q = s[j];
        bool multi = j + 2 < n && s[j + 1] == q && s[j + 2] == q;
        j += multi ? 3 : 1;
        while (j < n) {
            char c = s[j];
            if (c == '\\' && q == '"') { j += 2; continue; }
            if (c == '\n' && !multi) return false;
            if (c == q) {
                if (!multi) { j++; return true; }
                if (j + 2 < n && s[j + 1] == q && s[j + 2] == q) {
                    j += 3;
                    while (j < n && s[j] == q) j++; /* up to two quotes may close the content */
                    return true;
                }
            }
            j++;
        }
        return false;
    };
    /* counts the names of the key at s[j] (bare or quoted, separated by dots) */
    auto scan_key = [&](size_t &j) -> int {
        size_t start = j;
        int names = 0;
        for (;;) {
            while (j < n && (s[j] == ' ' || s[j] == '\t')) j++;
            if (j < n && (s[j] == '"' || s[j] == '\'')) {
                if (!skip_string(j)) return names; /* toml++ reports it */
            } else if (j < n && is_bare(s[j])) {
                while (j < n && is_bare(s[j])) j++;
            } else {
                break;
            }
            names++;
            while (j < n && (s[j] == ' ' || s[j] == '\t')) j++;
            if (j < n && s[j] == '.') { j++; continue; }
            break;
        }
        if (names > CD_MAX_KEY_NAMES) {
            std::string shown = s.substr(start, std::min<size_t>(j - start, 40));
            while (j - start > 40 && !shown.empty() && (shown.back() == '.' || shown.back() == ' ')) shown.pop_back();
            fail_at(loc_of(start), shown + (j - start > 40 ? "..." : ""),
                    "expected a key or table header of at most " + std::to_string(CD_MAX_KEY_NAMES) +
                        " dotted names, got " + std::to_string(names));
        }
        return names;
    };
    while (i < n) {
        char c = s[i];
        if (c == '\n') {
            if (st.empty()) expect_key = true;
            i++;
            continue;
        }
        if (c == ' ' || c == '\t' || c == '\r') { i++; continue; }
        if (c == '#') {
            while (i < n && s[i] != '\n') i++;
            continue;
        }
        if (expect_key && st.empty() && c == '[') { /* [table] or [[array.of.tables]] */
            bool aot = i + 1 < n && s[i + 1] == '[';
            size_t at = i;
            i += aot ? 2 : 1;
            table_depth = scan_key(i) + (aot ? 1 : 0);
            too_deep(at, table_depth);
            expect_key = false;
            continue;
        }
        if (expect_key && (st.empty() || st.back().c == '{') && (is_bare(c) || c == '"' || c == '\'')) {
            size_t at = i;
            int names = scan_key(i);
            val_depth = (st.empty() ? table_depth : st.back().depth) + names;
            too_deep(at, val_depth);
            expect_key = false;
            if (names == 0) i++;
            continue;
        }
        switch (c) {
        case '"':
        case '\'':
            if (!skip_string(i)) return;
            continue;
        case '[': /* an array at depth val_depth: its elements one deeper */
            st.push_back({c, val_depth});
            val_depth++;
            too_deep(i, val_depth);
            break;
        case '{': /* an inline table: its keys' names add to its depth */
            st.push_back({c, val_depth});
            expect_key = true;
            break;
        case ',':
            if (!st.empty() && st.back().c == '{') expect_key = true;
            else if (!st.empty()) val_depth = st.back().depth + 1;
            break;
        case ']':
        case '}':
            if (!st.empty()) st.pop_back();
            if (!st.empty() && st.back().c == '[') val_depth = st.back().depth + 1;
            expect_key = false;
            break;
        default:
            break;
        }
        i++;
    }
}

std::string file_kind(mode_t m)
{
    if (S_ISDIR(m)) return "a directory";
    if (S_ISCHR(m)) return "a character device";
    if (S_ISBLK(m)) return "a block device";
    if (S_ISFIFO(m)) return "a FIFO";
    if (S_ISSOCK(m)) return "a socket";
    return "not a plain file";
}

std::string too_large(unsigned long long bytes)
{
    char b[160];
    std::snprintf(b, sizeof b, "%.1f MiB (%llu bytes), more than the %llu MiB a scenario file may have",
                  (double)bytes / 1048576.0, bytes, CD_SCENARIO_MAX_BYTES >> 20);
    return b;
}

/* A scenario file that cannot be read: CD_EIO, located at the include entry
 * that named it (from; NULL for the main file). */
[[noreturn]] void refuse(const std::string &path, const Loc *from, const std::string &from_key, const std::string &why)
{
    if (!from) throw LoadError{CD_EIO, "cannot read scenario file '" + path + "': " + why};
    fail_at(*from, from_key, "cannot read included file '" + path + "': " + why, CD_EIO);
}

struct FileLoader {
    std::string text;                /* main file, then each include (once) with a header line */
    std::vector<std::string> stack;  /* canonical paths being loaded (cycle detection, depth) */
    std::vector<std::string> shown;  /* the same paths as written, for messages */
    /* a file included again (a diamond) is not read or parsed again: its
     * merged tree is copied from here, so includes take time linear in the
     * number of include entries, not exponential in the depth */
    std::unordered_map<std::string, NodeP> done;
    unsigned long long total = 0;    /* bytes read so far, all files */
    unsigned long long reused = 0;   /* values copied from the cache so far */

    static std::string canon(const std::string &p)
    {
        std::error_code ec;
        auto c = std::filesystem::weakly_canonical(std::filesystem::path(p), ec);
        return ec ? p : c.string();
    }

    /* Reads a whole regular file of at most CD_SCENARIO_MAX_BYTES (a device
     * such as /dev/zero, a FIFO or a directory would make the read hang,
     * never end or fail obscurely). The buffer is on the heap: a chain of
     * includes costs little stack per level. */
    std::string read(const std::string &path, const Loc *from, const std::string &from_key)
    {
        std::string content;
        struct stat sb;
        if (::stat(path.c_str(), &sb) != 0) refuse(path, from, from_key, std::strerror(errno));
        if (!S_ISREG(sb.st_mode)) refuse(path, from, from_key, "not a regular file (" + file_kind(sb.st_mode) + ")");
        if ((unsigned long long)sb.st_size > CD_SCENARIO_MAX_BYTES)
            refuse(path, from, from_key, too_large((unsigned long long)sb.st_size));
        FILE *f = std::fopen(path.c_str(), "rb");
        if (!f) refuse(path, from, from_key, std::strerror(errno));
        std::unique_ptr<FILE, int (*)(FILE *)> closer(f, std::fclose);
        content.reserve((size_t)sb.st_size);
        std::vector<char> buf(65536);
        size_t n;
        while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) {
            content.append(buf.data(), n);
            if (content.size() > CD_SCENARIO_MAX_BYTES) /* it grew since stat */
                refuse(path, from, from_key, too_large((unsigned long long)content.size()));
        }
        if (std::ferror(f)) refuse(path, from, from_key, "read error");
        total += content.size();
        if (total > CD_MAX_TOTAL_BYTES) {
            char b[160];
            std::snprintf(b, sizeof b, "the scenario and its includes together exceed %llu MiB (%llu bytes read)",
                          CD_MAX_TOTAL_BYTES >> 20, total);
            refuse(path, from, from_key, b);
        }
        return content;
    }

    /* Loads path (and its includes); from/from_key locate the include entry
     * that asked for it (NULL for the main file). */
    NodeP load(const std::string &path, const Loc *from, const std::string &from_key)
    {
        std::string cpath = canon(path);
        for (size_t i = 0; i < stack.size(); i++)
            if (stack[i] == cpath) {
                std::string cyc;
                for (size_t j = i; j < stack.size(); j++) cyc += shown[j] + " -> ";
                fail_at(*from, from_key, "include cycle: " + cyc + path + " (expected a file that does not include itself)");
            }
        auto hit = done.find(cpath);
        if (hit != done.end()) {
            /* a file included again costs its values, not its bytes: bounded
             * too (include = ["b.toml", "b.toml", ... 10^6 times]) */
            NodeP c = deep_copy(*hit->second, &reused);
            if (reused > CD_MAX_REUSED_VALUES)
                fail_at(*from, from_key,
                        "expected includes that repeat at most 10^7 values in all, got more (file '" + path +
                            "' included again and again)");
            return c;
        }
        if (from && stack.size() > (size_t)CD_MAX_INCLUDE_DEPTH)
            fail_at(*from, from_key,
                    "expected includes nested at most " + std::to_string(CD_MAX_INCLUDE_DEPTH) + " levels deep, got " +
                        shown[0] + " -> " + shown[1] + " -> ... -> " + shown.back() + " -> " + path);
        std::string content = read(path, from, from_key);
        if (from) text += "\n# ---- included file: " + path + " ----\n";
        text += content;

        Str file = std::make_shared<const std::string>(path);
        NodeP root;
        prescan(content, [&](size_t at) {
            Loc l;
            l.file = file;
            l.line = 1 + (int)std::count(content.begin(), content.begin() + (long)at, '\n');
            size_t nl = content.rfind('\n', at == 0 ? 0 : at - 1);
            l.col = (int)(at - (nl == std::string::npos || at == 0 ? 0 : nl + 1)) + 1;
            return l;
        });
        try {
            toml::table t = toml::parse(std::string_view(content), std::string_view(path));
            Loc top;
            top.file = file;
            top.line = top.col = 1;
            root = convert(t, file, top);
            root->loc = top;
        } catch (const toml::parse_error &pe) {
            Loc l;
            l.file = file;
            l.line = (int)pe.source().begin.line;
            l.col = (int)pe.source().begin.column;
            fail_at(l, "", "TOML syntax error: " + std::string(pe.description()));
        }

        Entry *inc = root->find("include");
        if (!inc) {
            unsigned long long n = 0;
            if (from) done.emplace(cpath, deep_copy(*root, &n)); /* the main file is never included again */
            return root;
        }
        std::vector<std::pair<std::string, Loc>> incs;
        Node &iv = *inc->val;
        if (iv.kind == NK::String) {
            incs.push_back({iv.sval, iv.loc});
        } else if (iv.kind == NK::Array) {
            for (size_t i = 0; i < iv.arr.size(); i++) {
                if (iv.arr[i]->kind != NK::String)
                    fail_at(iv.arr[i]->loc, idx("include", i),
                            "expected a file name (string), got " + render(*iv.arr[i]));
                incs.push_back({iv.arr[i]->sval, iv.arr[i]->loc});
            }
        } else {
            fail_at(iv.loc, "include", "expected an array of file names, got " + render(iv));
        }
        auto merged = std::make_shared<Node>();
        merged->kind = NK::Table;
        merged->loc = root->loc;
        std::filesystem::path dir = std::filesystem::path(path).parent_path();
        stack.push_back(cpath);
        shown.push_back(path);
        for (size_t i = 0; i < incs.size(); i++) {
            std::filesystem::path p(incs[i].first);
            std::string resolved = p.is_absolute() ? p.string() : (dir / p).string();
            std::string key = iv.kind == NK::String ? std::string("include") : idx("include", i);
            NodeP child = load(resolved, &incs[i].second, key);
            merge_into(*merged, *child);
        }
        stack.pop_back();
        shown.pop_back();
        root->tab.erase(root->tab.begin() + (inc - root->tab.data()));
        merge_into(*merged, *root);
        unsigned long long n = 0;
        if (from) done.emplace(cpath, deep_copy(*merged, &n));
        return merged;
    }
};

/* ---- --set overrides ---------------------------------------------------------- */

bool is_ident_char(char c) { return std::isalnum((unsigned char)c) || c == '_' || c == '-'; }

std::string trim(const std::string &s)
{
    size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

/* Parses the value of an override: TOML value syntax; a bare word (letters,
 * digits, _ - . /) that is not valid TOML is taken as a string. */
NodeP parse_override_value(const std::string &value, const Loc &L)
{
    NodeP out;
    std::string doc = "v = " + value;
    prescan(doc, [&](size_t) { return L; });
    try {
        toml::table t = toml::parse(std::string_view(doc), std::string_view("--set"));
        if (t.size() == 1 && t.contains("v")) {
            out = convert(*t.get("v"), nullptr, L);
        }
    } catch (const toml::parse_error &) {
        out = nullptr;
    }
    if (!out) {
        bool bare = !value.empty() && (std::isalpha((unsigned char)value[0]) || value[0] == '_');
        for (char c : value)
            if (!(is_ident_char(c) || c == '.' || c == '/')) bare = false;
        if (!bare)
            fail_at(L, "",
                    "cannot parse the value '" + value +
                        "' (expected a TOML value: a number, \"string\", [array] or {table})");
        out = std::make_shared<Node>();
        out->kind = NK::String;
        out->sval = value;
    }
    set_loc_all(*out, L);
    return out;
}

/* a --set key path split into segments: ident ('[' int ']')* separated by '.' */
struct OvSeg {
    std::string id;
    std::vector<size_t> ix;
};

std::vector<OvSeg> parse_key_path(const std::string &path, const Loc &L)
{
    std::vector<OvSeg> segs;
    size_t i = 0;
    while (i < path.size()) {
        OvSeg s;
        while (i < path.size() && is_ident_char(path[i])) s.id += path[i++];
        if (s.id.empty()) fail_at(L, "", "bad key path '" + path + "' (expected names separated by '.', indices as [N])");
        while (i < path.size() && path[i] == '[') {
            size_t j = path.find(']', i);
            std::string num = j == std::string::npos ? "" : path.substr(i + 1, j - i - 1);
            if (num.empty() || num.find_first_not_of("0123456789") != std::string::npos)
                fail_at(L, "", "bad index in key path '" + path + "' (expected [N], N >= 0)");
            /* at most 9 digits: no array of the loader has 10^9 elements,
             * and the conversion cannot overflow */
            if (num.size() > 9)
                fail_at(L, "", "bad index [" + num + "] in key path '" + path + "' (expected [N], 0 <= N < 10^9)");
            s.ix.push_back((size_t)std::strtoul(num.c_str(), nullptr, 10));
            i = j + 1;
        }
        segs.push_back(s);
        if (i < path.size()) {
            if (path[i] != '.') { /* the whole character, not one byte of a UTF-8 sequence */
                size_t e = i + 1;
                if ((unsigned char)path[i] >= 0xC0)
                    while (e < path.size() && ((unsigned char)path[e] & 0xC0) == 0x80) e++;
                fail_at(L, "", "bad key path '" + path + "' (unexpected '" + path.substr(i, e - i) + "')");
            }
            i++;
            if (i == path.size()) fail_at(L, "", "bad key path '" + path + "' (ends with '.')");
        }
    }
    return segs;
}

void apply_override(NodeP &root, const std::string &ov)
{
    Loc L;
    L.ovr = std::make_shared<const std::string>(ov);
    size_t eq = ov.find('=');
    if (eq == std::string::npos) fail_at(L, "", "expected KEY.PATH=VALUE");
    std::string path = trim(ov.substr(0, eq)), value = trim(ov.substr(eq + 1));
    if (path.empty()) fail_at(L, "", "expected KEY.PATH=VALUE (the key path is empty)");
    if (value.empty()) fail_at(L, "", "expected KEY.PATH=VALUE (the value is empty)");

    std::vector<OvSeg> segs = parse_key_path(path, L);
    if (segs[0].id == "include") fail_at(L, "", "'include' cannot be changed by --set");
    if (segs.size() > (size_t)CD_MAX_KEY_NAMES)
        fail_at(L, "", "expected a key path of at most " + std::to_string(CD_MAX_KEY_NAMES) + " names, got " +
                           std::to_string(segs.size()));

    NodeP value_node = parse_override_value(value, L);
    NodeP *slot = &root;
    std::string shown;  /* the canonical path walked so far, for messages */
    for (size_t k = 0; k < segs.size(); k++) {
        const OvSeg &s = segs[k];
        bool last = k + 1 == segs.size();
        Node &cur = **slot;
        if (cur.kind == NK::Table) {
            Entry *e = cur.find(s.id);
            if (!e) {
                if (!s.ix.empty())
                    fail_at(L, join(shown, s.id), "cannot index a key that does not exist");
                /* a missing key is created (the schema check then names it if it is not a known key) */
                Entry ne;
                ne.key = s.id;
                ne.kloc = L;
                if (last) {
                    ne.val = value_node;
                } else {
                    ne.val = std::make_shared<Node>();
                    ne.val->kind = NK::Table;
                    ne.val->loc = L;
                    /* KEY.x = V on a missing KEY: a table {x = V}, which the
                     * schema refuses where an array is expected; render()
                     * says why (no table of the schema has a key x, y or z) */
                    const OvSeg &nx = segs[k + 1];
                    if (k + 2 == segs.size() && nx.ix.empty() && (nx.id == "x" || nx.id == "y" || nx.id == "z"))
                    {
                        ne.val->component = nx.id;
                        ne.val->component_of = join(shown, s.id);
                    }
                }
                cur.tab.push_back(ne);
                slot = &cur.tab.back().val;
                shown = join(shown, s.id);
                if (last) return;
                continue;
            }
            slot = &e->val;
            shown = join(shown, s.id);
        } else if (cur.kind == NK::Array && (s.id == "x" || s.id == "y" || s.id == "z") && !cur.arr.empty() &&
                   (cur.arr[0]->kind == NK::Float || cur.arr[0]->kind == NK::Int)) {
            /* a vector's component by name: position.x is position[0] */
            size_t c = (size_t)(s.id[0] - 'x');
            if (c >= cur.arr.size())
                fail_at(L, shown, "no component '" + s.id + "': the value has " + std::to_string(cur.arr.size()) +
                                      " elements");
            slot = &cur.arr[c];
            shown = idx(shown, c);
        } else if (cur.kind == NK::Array) {
            /* select an element of an array of tables by its name */
            std::vector<std::string> names;
            NodeP *hit = nullptr;
            size_t hit_i = 0;
            for (size_t j = 0; j < cur.arr.size(); j++) {
                const std::string *n = name_of(*cur.arr[j]);
                if (!n) continue;
                names.push_back(*n);
                if (*n == s.id && !hit) { hit = &cur.arr[j]; hit_i = j; }
            }
            if (!hit && cur.arr.size() == 1 && cur.arr[0]->kind == NK::Table &&
                (cur.arr[0]->find(s.id) || closest(s.id, names).empty())) {
                /* the only element of the array, left implicit: target.position
                 * is target[0].position when there is one [[target]] (not when
                 * the word looks like a misspelt name of that element) */
                slot = &cur.arr[0];
                shown = idx(shown, 0);
                k--;
                continue;
            }
            if (!hit) {
                if (names.empty() && !cur.arr.empty() && (cur.arr[0]->kind == NK::Float || cur.arr[0]->kind == NK::Int))
                    fail_at(L, shown, "no component '" + s.id + "' (expected x, y, z or an index [N])");
                if (names.empty())
                    fail_at(L, shown, "no element named '" + s.id + "' (the elements have no names; use an index [N])");
                fail_at(L, shown, "no element named '" + s.id + "'" + hint(s.id, names));
            }
            slot = hit;
            shown = idx(shown, hit_i);
        } else if (s.id == "x" || s.id == "y" || s.id == "z") {
            fail_at(L, shown, "no component '" + s.id + "': the value is " + render(cur) + ", not an array of numbers");
        } else {
            fail_at(L, shown, "expected a table to select '" + s.id + "' in, got " + render(cur));
        }
        for (size_t x : s.ix) {
            Node &n = **slot;
            if (n.kind != NK::Array)
                fail_at(L, shown, "cannot index [" + std::to_string(x) + "]: the value is " + render(n) + ", not an array");
            if (x >= n.arr.size())
                fail_at(L, shown,
                        "index [" + std::to_string(x) + "] out of range (the array has " + std::to_string(n.arr.size()) +
                            " elements)");
            slot = &n.arr[x];
            shown = idx(shown, x);
        }
        if (last) {
            *slot = value_node;
            return;
        }
    }
}

/* ---- typed readers ------------------------------------------------------------- */

enum class Range { Any, Pos, NonNeg, Ge1 };

const char *range_text(Range r)
{
    switch (r) {
    case Range::Any: return "a finite number";
    case Range::Pos: return "a positive number";
    case Range::NonNeg: return "a number >= 0";
    case Range::Ge1: return "a number >= 1";
    }
    return "a number";
}

double num_of(const Node &n, const std::string &path, Range r)
{
    double v;
    if (n.kind == NK::Int) v = (double)n.ival;
    else if (n.kind == NK::Float) v = n.fval;
    else fail_at(n.loc, path, std::string("expected ") + range_text(r) + ", got " + render(n));
    bool ok = std::isfinite(v);
    if (ok && r == Range::Pos && v > 0 && !std::isnormal(v))
        fail_at(n.loc, path, "expected a positive number of at least 2.2e-308 (a subnormal number has lost its precision), got " + render(n));
    if (ok) switch (r) {
        case Range::Any: break;
        case Range::Pos: ok = v > 0; break;
        case Range::NonNeg: ok = v >= 0; break;
        case Range::Ge1: ok = v >= 1; break;
        }
    if (!ok) fail_at(n.loc, path, std::string("expected ") + range_text(r) + ", got " + render(n));
    return v;
}

/* An array of exactly k numbers (each in range r). */
void vec_of(const Node &n, const std::string &path, int k, double *out, Range r = Range::Any,
            const char *what = nullptr)
{
    std::string exp = what ? std::string(what) : "an array of " + std::to_string(k) + " numbers";
    if (n.kind != NK::Array || (int)n.arr.size() != k) fail_at(n.loc, path, "expected " + exp + ", got " + render(n));
    for (int i = 0; i < k; i++) out[i] = num_of(*n.arr[(size_t)i], idx(path, (size_t)i), r);
}

std::string str_of(const Node &n, const std::string &path)
{
    if (n.kind != NK::String) fail_at(n.loc, path, "expected a string, got " + render(n));
    return n.sval;
}

std::string choice_of(const Node &n, const std::string &path, const std::vector<std::string> &choices)
{
    std::string s = str_of(n, path);
    for (auto &c : choices)
        if (c == s) return s;
    std::string m = "expected one of " + list(choices) + ", got '" + s + "'";
    std::string c = closest(s, choices);
    if (!c.empty()) m += " (did you mean '" + c + "'?)";
    fail_at(n.loc, path, m);
}

/* Names: letters, digits, '_' and '-' (they are used in "system/link" references and --set paths). */
std::string name_of_node(const Node &n, const std::string &path)
{
    std::string s = str_of(n, path);
    bool ok = !s.empty();
    for (char c : s)
        if (!is_ident_char(c)) ok = false;
    if (!ok) fail_at(n.loc, path, "expected a name made of letters, digits, '_' and '-', got '" + s + "'");
    return s;
}

long long int_of(const Node &n, const std::string &path, long long minv)
{
    std::string exp = "expected an integer >= " + std::to_string(minv);
    long long v = 0;
    if (n.kind == NK::Int) v = n.ival;
    else if (n.kind == NK::Float && std::isfinite(n.fval) && n.fval == std::floor(n.fval) && std::fabs(n.fval) < 9e18)
        v = (long long)n.fval;
    else fail_at(n.loc, path, exp + ", got " + render(n));
    if (v < minv) fail_at(n.loc, path, exp + ", got " + render(n));
    return v;
}

/* A table being read: checks unknown keys on construction. */
struct Tab {
    Node *n;
    std::string path;
    Tab(Node *node, std::string p, const std::vector<std::string> &allowed) : n(node), path(std::move(p))
    {
        for (auto &e : n->tab)
            if (std::find(allowed.begin(), allowed.end(), e.key) == allowed.end())
                fail_at(e.kloc, join(path, e.key), "unknown key" + hint(e.key, allowed));
    }
    Entry *get(const char *k) const { return n->find(k); }
    Node &need(const char *k, const std::string &expected) const
    {
        Entry *e = n->find(k);
        if (!e) fail_at(n->loc, join(path, k), "missing required key (expected " + expected + ")");
        return *e->val;
    }
    std::string kp(const char *k) const { return join(path, k); }
    double num(const char *k, double def, Range r) const
    {
        Entry *e = get(k);
        return e ? num_of(*e->val, kp(k), r) : def;
    }
    double need_num(const char *k, Range r) const { return num_of(need(k, range_text(r)), kp(k), r); }
    void vec(const char *k, int dim, double *out, Range r = Range::Any) const
    {
        Entry *e = get(k);
        if (e) vec_of(*e->val, kp(k), dim, out, r);
    }
};

bool bool_of(const Node &n, const std::string &path)
{
    if (n.kind != NK::Bool) fail_at(n.loc, path, "expected true or false, got " + render(n));
    return n.bval;
}

/* rows [[t, v], ...] with strictly increasing t */
void rows_of(const Node &tb, const std::string &p, const char *what, std::vector<double> &tt, std::vector<double> &tv)
{
    if (tb.kind != NK::Array || tb.arr.empty())
        fail_at(tb.loc, p, std::string("expected a non-empty array of ") + what + " rows, got " + render(tb));
    for (size_t i = 0; i < tb.arr.size(); i++) {
        double r[2];
        vec_of(*tb.arr[i], idx(p, i), 2, r, Range::Any, (std::string("a row ") + what).c_str());
        if (i > 0 && !(r[0] > tt.back()))
            fail_at(tb.arr[i]->loc, idx(p, i),
                    "expected times strictly increasing, got t = " + fmt_num(r[0]) + " after t = " + fmt_num(tt.back()));
        tt.push_back(r[0]);
        tv.push_back(r[1]);
    }
}

/* A child table (value must be a table). */
Node *table_of(Node &n, const std::string &path)
{
    if (n.kind != NK::Table) fail_at(n.loc, path, "expected a table, got " + render(n));
    return &n;
}

/* A list of tables: an array of tables, or a single table taken as one. */
std::vector<Node *> tables_of(Node &n, const std::string &path, const char *header)
{
    std::vector<Node *> out;
    if (n.kind == NK::Table) {
        out.push_back(&n);
        return out;
    }
    if (n.kind == NK::Array) {
        for (auto &a : n.arr) {
            if (a->kind != NK::Table)
                fail_at(a->loc, path, std::string("expected an array of tables (") + header + "), got " + render(n));
            out.push_back(a.get());
        }
        return out;
    }
    fail_at(n.loc, path, std::string("expected an array of tables (") + header + "), got " + render(n));
}

/* ---- geometry helpers ----------------------------------------------------------- */

/* Eigenvalues of a symmetric 3x3 (trigonometric method, as in model.c). */
void sym_eig3(const double I[9], double ev[3])
{
    double p1 = I[1] * I[1] + I[2] * I[2] + I[5] * I[5];
    double q = (I[0] + I[4] + I[8]) / 3.0;
    if (p1 == 0) {
        ev[0] = I[0]; ev[1] = I[4]; ev[2] = I[8];
        return;
    }
    double p2 = (I[0] - q) * (I[0] - q) + (I[4] - q) * (I[4] - q) + (I[8] - q) * (I[8] - q) + 2 * p1;
    double p = std::sqrt(p2 / 6.0), B[9];
    for (int i = 0; i < 9; i++) B[i] = (I[i] - (i % 4 == 0 ? q : 0.0)) / p;
    double r = 0.5 * (B[0] * (B[4] * B[8] - B[5] * B[7]) - B[1] * (B[3] * B[8] - B[5] * B[6]) +
                      B[2] * (B[3] * B[7] - B[4] * B[6]));
    double phi = r <= -1 ? CD_PI / 3 : (r >= 1 ? 0 : std::acos(r) / 3);
    ev[0] = q + 2 * p * std::cos(phi);
    ev[2] = q + 2 * p * std::cos(phi + 2 * CD_PI / 3);
    ev[1] = 3 * q - ev[0] - ev[2];
}

/* inertia: 3 numbers (principal, diagonal), 6 numbers (xx yy zz xy xz yz: the
 * tensor's entries, I_xy = -sum m x y) or a 3x3 array; then physically checked. */
void inertia_of(const Node &n, const std::string &path, double I[9])
{
    const char *exp = "expected 3 numbers (principal moments), 6 numbers (xx, yy, zz, xy, xz, yz) or a 3x3 array";
    if (n.kind != NK::Array) fail_at(n.loc, path, std::string(exp) + ", got " + render(n));
    std::memset(I, 0, 9 * sizeof(double));
    if (n.arr.size() == 3 && n.arr[0]->kind == NK::Array) {
        for (size_t r = 0; r < 3; r++) vec_of(*n.arr[r], idx(path, r), 3, I + 3 * r, Range::Any, "a row of 3 numbers");
        double tol = 1e-9 * (std::fabs(I[0]) + std::fabs(I[4]) + std::fabs(I[8]));
        if (std::fabs(I[1] - I[3]) > tol || std::fabs(I[2] - I[6]) > tol || std::fabs(I[5] - I[7]) > tol)
            fail_at(n.loc, path, "expected a symmetric inertia matrix, got " + render(n));
    } else if (n.arr.size() == 3) {
        double d[3];
        vec_of(n, path, 3, d);
        I[0] = d[0]; I[4] = d[1]; I[8] = d[2];
    } else if (n.arr.size() == 6) {
        double d[6];
        vec_of(n, path, 6, d);
        I[0] = d[0]; I[4] = d[1]; I[8] = d[2];
        I[1] = I[3] = d[3];
        I[2] = I[6] = d[4];
        I[5] = I[7] = d[5];
    } else {
        fail_at(n.loc, path, std::string(exp) + ", got " + render(n));
    }
    double ev[3];
    sym_eig3(I, ev);
    std::string evs = "(" + fmt_num(ev[0]) + ", " + fmt_num(ev[1]) + ", " + fmt_num(ev[2]) + ")";
    if (!(ev[0] > 0 && ev[1] > 0 && ev[2] > 0))
        fail_at(n.loc, path, "expected a positive definite inertia, got principal moments " + evs);
    double tol = 1e-9 * (ev[0] + ev[1] + ev[2]);
    if (ev[0] + ev[1] < ev[2] - tol || ev[1] + ev[2] < ev[0] - tol || ev[0] + ev[2] < ev[1] - tol)
        fail_at(n.loc, path,
                "expected principal moments obeying the triangle inequality (each <= the sum of the other two), got " +
                    evs);
}

const double DEG = CD_PI / 180.0;

/* Orientation from rpy_deg or quaternion (exclusive); identity if neither. */
void rotation_of(const Tab &t, double R[9], const char *extra_exclusive = nullptr)
{
    Entry *rpy = t.get("rpy_deg"), *qu = t.get("quaternion");
    Entry *ex = extra_exclusive ? t.get(extra_exclusive) : nullptr;
    if (rpy && qu) fail_at(qu->kloc, t.kp("quaternion"), "give either rpy_deg or quaternion, not both");
    cd_m3_identity(R);
    if (rpy) {
        if (ex) fail_at(ex->kloc, t.kp(extra_exclusive), std::string("give either rpy_deg or ") + extra_exclusive + ", not both");
        double a[3];
        vec_of(*rpy->val, t.kp("rpy_deg"), 3, a, Range::Any, "an array of 3 angles [roll, pitch, yaw] in degrees");
        cd_m3_from_rpy(R, a[0] * DEG, a[1] * DEG, a[2] * DEG);
    } else if (qu) {
        if (ex) fail_at(ex->kloc, t.kp(extra_exclusive), std::string("give either quaternion or ") + extra_exclusive + ", not both");
        double q[4];
        vec_of(*qu->val, t.kp("quaternion"), 4, q, Range::Any, "an array of 4 numbers [w, x, y, z]");
        if (!cd_quat_normalize(q)) fail_at(qu->val->loc, t.kp("quaternion"), "expected a non-zero quaternion [w, x, y, z], got " + render(*qu->val));
        cd_quat_to_m3(R, q);
    }
}

/* A convex shape's vertices must span a volume. The greedy tetrahedron (a
 * vertex; the farthest from it; the farthest from their line; the farthest
 * from their plane) must be thicker than 1e-6 of the hull's size (the
 * model's hull search, src/model/model.c, takes 1e-9 of it as flat). Checked
 * here, in O(n), so that the message names the table and key rather than
 * the model's finalize step. */
void hull_volume_check(const std::vector<double> &v, const Node &vn, const std::string &path)
{
    size_t n = v.size() / 3, i, a = 0, b = 0, c = 0;
    double ctr[3] = {0, 0, 0}, size = 0, best, e1[3], nrm[3], t[3];
    for (i = 0; i < n; i++) cd_v3_axpy(ctr, 1.0 / (double)n, &v[3 * i]);
    for (i = 0; i < n; i++) {
        cd_v3_sub(t, &v[3 * i], ctr);
        size = std::max(size, cd_v3_norm(t));
    }
    std::string what = "expected vertices spanning a volume (not all on one plane), got ";
    if (!(size > 0)) fail_at(vn.loc, path, what + "a single point");
    best = -1;
    for (i = 0; i < n; i++) {
        cd_v3_sub(t, &v[3 * i], &v[0]);
        if (cd_v3_norm(t) > best) { best = cd_v3_norm(t); b = i; }
    }
    cd_v3_sub(e1, &v[3 * b], &v[3 * a]);
    cd_v3_normalize(e1);
    best = -1;
    for (i = 0; i < n; i++) {
        double w[3];
        cd_v3_sub(t, &v[3 * i], &v[3 * a]);
        cd_v3_cross(w, t, e1);
        if (cd_v3_norm(w) > best) { best = cd_v3_norm(w); c = i; }
    }
    if (!(best > 1e-6 * size)) fail_at(vn.loc, path, what + "points on one line");
    cd_v3_sub(t, &v[3 * c], &v[3 * a]);
    cd_v3_cross(nrm, e1, t);
    cd_v3_normalize(nrm);
    best = 0;
    for (i = 0; i < n; i++) {
        cd_v3_sub(t, &v[3 * i], &v[3 * a]);
        best = std::max(best, std::fabs(cd_v3_dot(t, nrm)));
    }
    if (!(best > 1e-6 * size))
        fail_at(vn.loc, path, what + "points on one plane (thickness " + fmt_num(best) + " m for a size of " +
                                  fmt_num(size) + " m)");
}

/* Rotation taking +z onto the unit vector n (the smallest rotation). */
void rot_z_to(const double nin[3], double R[9])
{
    double n[3] = {nin[0], nin[1], nin[2]}, z[3] = {0, 0, 1}, a[3];
    cd_v3_normalize(n);
    double c = cd_v3_dot(z, n);
    cd_v3_cross(a, z, n);
    double s = cd_v3_norm(a);
    if (s < 1e-12) {
        cd_m3_identity(R);
        if (c < 0) { R[4] = -1; R[8] = -1; } /* rotation by pi about x */
        return;
    }
    cd_v3_scale(a, a, 1.0 / s);
    cd_m3_axis_angle(R, a, std::atan2(s, c));
}

/* ---- the model builder ------------------------------------------------------------- */

struct ModelDel {
    void operator()(cd_model *m) const { cd_model_free(m); }
};

struct BodyInfo {
    std::string name;
    int id;
    int ncp = 0;
};
struct SysInfo {
    std::string name;
    int id;
    bool is_target = false;
    Loc frame_loc;                 /* a target given in the palm's frame: where it says so */
    bool in_palm = false;
    Loc loc;
    std::string path;
    std::vector<BodyInfo> bodies;  /* base first (named "base" here) */
    std::vector<std::pair<std::string, int>> shapes;
    /* name -> index in bodies / shapes: a system of 10^5 links or shapes,
     * and 10^5 pairs naming them, build in linear time */
    std::unordered_map<std::string, size_t> body_at, shape_at;
    int ncp = 0;                   /* check points on all its bodies */
    std::vector<std::string> body_names() const
    {
        std::vector<std::string> v;
        for (auto &b : bodies) v.push_back(b.name);
        return v;
    }
    std::vector<std::string> shape_names() const
    {
        std::vector<std::string> v;
        for (auto &x : shapes) v.push_back(x.first);
        return v;
    }
    void add_body(const std::string &n, int id)
    {
        body_at.emplace(n, bodies.size());
        bodies.push_back(BodyInfo{n, id, 0});
    }
};

struct LawState {
    cd_contact_law law;
    bool kt_set = false, dt_set = false, mu_set = false;
    int d_law = CD_DAMP_LINEAR; /* the damping law D was given for (its units differ) */
};

const std::vector<std::string> LAW_KEYS = {"K", "D", "p", "q", "K_t", "D_t", "p_t", "q_t", "mu_max", "mu", "rule", "pull",
                                           "damping_law"};

struct Builder {
    std::unique_ptr<cd_model, ModelDel> m;
    std::vector<SysInfo> sys;
    std::set<std::string> pair_names;
    std::unordered_map<std::string, size_t> sys_at;
    size_t hull_vertices = 0;  /* all convex shapes so far */
    cd_error err{};
    Loc file_loc;

    /* builder call failed: prefix its message with the table's location */
    [[noreturn]] void builder_fail(const Loc &l, const std::string &path)
    {
        fail_at(l, path, err.msg, err.status == CD_ENOMEM ? CD_ENOMEM : CD_EINVAL);
    }
    /* a body's builder refused it: at the key its message is about (the
     * inertia, the mass) when the table gives it, else at the table. The word
     * is matched with its spaces: a name (letters, digits, '_', '-') that
     * holds it, as in link 'inertia_wheel', is not taken for it */
    [[noreturn]] void body_fail(const Tab &t, const Loc &l, const std::string &path)
    {
        for (const char *k : {"inertia", "mass"})
            if (std::strstr(err.msg, (std::string(" ") + k + " ").c_str()))
                if (Entry *e = t.get(k)) builder_fail(e->val->loc, t.kp(k));
        builder_fail(l, path);
    }

    std::vector<std::string> sys_names() const
    {
        std::vector<std::string> v;
        for (auto &s : sys) v.push_back(s.name);
        return v;
    }
    SysInfo *find_sys(const std::string &n)
    {
        auto it = sys_at.find(n);
        return it == sys_at.end() ? nullptr : &sys[it->second];
    }

    /* checkpoints = [[x, y, z, r], ...] on body b */
    void checkpoints(const Tab &t, SysInfo &s, BodyInfo &b)
    {
        Entry *e = t.get("checkpoints");
        if (!e) return;
        Node &a = *e->val;
        std::string p = t.kp("checkpoints");
        if (a.kind != NK::Array) fail_at(a.loc, p, "expected an array of [x, y, z, radius] rows, got " + render(a));
        for (size_t i = 0; i < a.arr.size(); i++) {
            double v[4];
            vec_of(*a.arr[i], idx(p, i), 4, v, Range::Any, "[x, y, z, radius] (metres)");
            if (!(v[3] >= 0)) fail_at(a.arr[i]->arr[3]->loc, idx(idx(p, i), 3), "expected a radius >= 0, got " + fmt_num(v[3]));
            if (cd_model_add_checkpoint(m.get(), b.id, v, v[3], &err) < 0) builder_fail(a.arr[i]->loc, idx(p, i));
            b.ncp++;
            s.ncp++;
        }
    }

    void shape(Node &node, const std::string &path, SysInfo &s, int body, const char *default_name)
    {
        Tab t(&node, path,
              {"name", "type", "position", "rpy_deg", "quaternion", "normal", "radius", "length", "size", "vertices",
               "height", "post"});
        std::string name;
        if (Entry *e = t.get("name")) name = name_of_node(*e->val, t.kp("name"));
        else if (default_name) name = default_name;
        else t.need("name", "a name (shapes are referenced as \"system/name\")");
        if (s.shape_at.count(name))
            fail_at(t.get("name") ? t.get("name")->val->loc : node.loc, t.kp("name"),
                    "expected a shape name unique in system '" + s.name + "', got '" + name + "' twice");
        std::vector<std::string> types = {"plane", "sphere", "box", "cylinder", "capsule", "convex", "handrail"};
        std::string ty = choice_of(t.need("type", "one of " + list(types)), t.kp("type"), types);
        if (ty == "handrail") { handrail(t, node, path, s, body, name); return; }
        int type = cd_shape_type_from_name(ty.c_str());
        /* which size keys apply to which type */
        std::vector<std::string> takes;
        if (ty == "plane") takes = {"normal"};
        else if (ty == "sphere") takes = {"radius"};
        else if (ty == "box") takes = {"size"};
        else if (ty == "cylinder" || ty == "capsule") takes = {"radius", "length"};
        else takes = {"vertices"};
        for (const char *k : {"normal", "radius", "length", "size", "vertices", "height", "post"})
            if (Entry *e = t.get(k))
                if (std::find(takes.begin(), takes.end(), k) == takes.end())
                    fail_at(e->kloc, t.kp(k), "does not apply to a " + ty + " shape (it takes: " + list(takes) + ")");
        cd_shape_desc sd = cd_shape_desc_default();
        sd.type = type;
        t.vec("position", 3, sd.pos);
        rotation_of(t, sd.rot, "normal");
        std::vector<double> verts;
        if (ty == "plane") {
            if (Entry *e = t.get("normal")) {
                double nrm[3];
                vec_of(*e->val, t.kp("normal"), 3, nrm);
                if (!(cd_v3_norm(nrm) > 1e-12)) fail_at(e->val->loc, t.kp("normal"), "expected a non-zero vector, got " + render(*e->val));
                rot_z_to(nrm, sd.rot);
            }
        } else if (ty == "sphere") {
            sd.radius = t.need_num("radius", Range::Pos);
        } else if (ty == "box") {
            vec_of(t.need("size", "an array of 3 positive edge lengths [m]"), t.kp("size"), 3, sd.size, Range::Pos);
        } else if (ty == "cylinder" || ty == "capsule") {
            sd.radius = t.need_num("radius", Range::Pos);
            sd.length = t.need_num("length", Range::Pos);
        } else {
            const Node &vn = t.need("vertices", "an array of at least 4 [x, y, z] points");
            if (vn.kind != NK::Array || vn.arr.size() < 4)
                fail_at(vn.loc, t.kp("vertices"), "expected an array of at least 4 [x, y, z] points, got " + render(vn));
            if (vn.arr.size() > CD_MAX_HULL_VERTICES)
                fail_at(vn.loc, t.kp("vertices"),
                        "expected at most " + std::to_string(CD_MAX_HULL_VERTICES) + " [x, y, z] points, got " +
                            std::to_string(vn.arr.size()) + " (the hull is built by brute force)");
            hull_vertices += vn.arr.size();
            if (hull_vertices > CD_MAX_TOTAL_HULL_VERTICES)
                fail_at(vn.loc, t.kp("vertices"),
                        "expected at most " + std::to_string(CD_MAX_TOTAL_HULL_VERTICES) +
                            " vertices in all convex shapes together, got " + std::to_string(hull_vertices) +
                            " with this one");
            for (size_t i = 0; i < vn.arr.size(); i++) {
                double v[3];
                vec_of(*vn.arr[i], idx(t.kp("vertices"), i), 3, v);
                verts.insert(verts.end(), v, v + 3);
            }
            hull_volume_check(verts, vn, t.kp("vertices"));
        }
        sd.verts = verts.empty() ? nullptr : verts.data();
        sd.nvert = (int)(verts.size() / 3);
        int id = cd_build_shape(m.get(), body, &sd, &err);
        if (id < 0) builder_fail(node.loc, path);
        s.shape_at.emplace(name, s.shapes.size());
        s.shapes.push_back({name, id});
    }

    /* A handrail fixture (ISS-era EVA handrail): a round bar of `radius` and
     * `length` along the shape's x axis, `height` above its base plane z = 0,
     * on two square posts of side `post` (default 2 radius) at its ends.
     * Three shapes: NAME_bar (capsule), NAME_post0, NAME_post1 (boxes). */
    void handrail(const Tab &t, Node &node, const std::string &path, SysInfo &s, int body, const std::string &name)
    {
        for (const char *k : {"normal", "size", "vertices"})
            if (Entry *e = t.get(k)) fail_at(e->kloc, t.kp(k), "does not apply to a handrail shape (it takes: 'radius', 'length', 'height', 'post')");
        cd_shape_desc sd = cd_shape_desc_default();
        sd.type = CD_SHAPE_HANDRAIL;
        t.vec("position", 3, sd.pos);
        rotation_of(t, sd.rot, "normal");
        double r = t.need_num("radius", Range::Pos), L = t.need_num("length", Range::Pos), h = t.need_num("height", Range::Pos);
        double w = t.num("post", 2 * r, Range::Pos);
        if (!(L > 2 * w)) fail_at(t.get("length")->val->loc, t.kp("length"), "expected a handrail longer than its two posts (" + fmt_num(2 * w) + " m), got " + fmt_num(L));
        if (!(h > r)) fail_at(t.get("height")->val->loc, t.kp("height"), "expected the bar's height above its base > its radius " + fmt_num(r) + ", got " + fmt_num(h));
        sd.radius = r;
        sd.length = L;
        sd.height = h;
        sd.post = w;
        const char *suffix[3] = {"_bar", "_post0", "_post1"};
        for (const char *sf : suffix)
            if (s.shape_at.count(name + sf)) fail_at(node.loc, t.kp("name"), "expected shape names unique in system '" + s.name + "', got '" + name + sf + "' twice");
        int id = cd_build_shape(m.get(), body, &sd, &err);
        if (id < 0) builder_fail(node.loc, path);
        for (int k = 0; k < 3; k++) {
            s.shape_at.emplace(name + suffix[k], s.shapes.size());
            s.shapes.push_back({name + suffix[k], id + k});
        }
    }

    void shapes(const Tab &t, SysInfo &s, int body)
    {
        Entry *e = t.get("shape");
        if (!e) return;
        std::string p = t.kp("shape");
        auto list = tables_of(*e->val, p, "[[...shape]]");
        for (size_t i = 0; i < list.size(); i++)
            shape(*list[i], e->val->kind == NK::Array ? idx(p, i) : p, s, body, nullptr);
    }

    /* The law keys of an actuator table (shared by a link's `actuator` and the
     * top-level [[actuator]] with a transmission): fills a, with the table
     * rows in tt/tv; `extra` are the keys the caller handles. */
    void actuator_law(Node &node, bool revolute, const std::vector<std::string> &extra,
                      cd_actuator_desc &a, std::vector<double> &tt, std::vector<double> &tv, Tab &t)
    {
        std::vector<std::string> types = {"none", "constant", "table", "steps", "pd"};
        std::string ty = choice_of(t.need("type", "one of " + list(types)), t.kp("type"), types);
        std::vector<std::string> takes;
        if (ty == "constant") takes = {"tau"};
        else if (ty == "table" || ty == "steps") takes = {"table"};
        else if (ty == "pd") takes = {"kp", "kd", revolute ? "qref_deg" : "qref", "tau0"};
        for (auto &e : node.tab) {
            if (e.key == "type" || e.key == "motor") continue;
            if (std::find(extra.begin(), extra.end(), e.key) != extra.end()) continue;
            if (std::find(takes.begin(), takes.end(), e.key) != takes.end()) continue;
            if (ty == "pd" && (e.key == "qref" || e.key == "qref_deg"))
                fail_at(e.kloc, t.kp(e.key.c_str()),
                        revolute ? "a revolute joint's set-point is qref_deg [deg]"
                                 : "a prismatic joint's set-point is qref [m]");
            fail_at(e.kloc, t.kp(e.key.c_str()),
                    "does not apply to a '" + ty + "' actuator" +
                        (takes.empty() ? std::string(" (it takes no parameters)") : " (it takes: " + list(takes) + ")"));
        }
        if (ty == "none") {
            a.type = CD_ACT_NONE;
        } else if (ty == "constant") {
            a.type = CD_ACT_CONSTANT;
            a.tau0 = t.need_num("tau", Range::Any);
        } else if (ty == "table" || ty == "steps") {
            a.type = ty == "table" ? CD_ACT_TABLE : CD_ACT_STEPS;
            rows_of(t.need("table", "an array of [t, tau] rows"), t.kp("table"), "[t, tau]", tt, tv);
            a.tbl_t = tt.data();
            a.tbl_v = tv.data();
            a.ntbl = (int)tt.size();
        } else {
            a.type = CD_ACT_PD;
            a.kp = t.need_num("kp", Range::NonNeg);
            a.kd = t.num("kd", 0.0, Range::NonNeg);
            a.qref = revolute ? t.num("qref_deg", 0.0, Range::Any) * DEG : t.num("qref", 0.0, Range::Any);
            a.tau0 = t.num("tau0", 0.0, Range::Any);
        }
        if (Entry *e = t.get("motor")) {
            std::string mp = t.kp("motor");
            Tab mt(table_of(*e->val, mp), mp, {"stall_torque", "noload_speed"});
            a.stall_torque = mt.need_num("stall_torque", Range::Pos);
            a.noload_speed = mt.need_num("noload_speed", Range::Pos);
        }
    }

    void actuator(Node &node, const std::string &path, int body, bool revolute)
    {
        static const std::vector<std::string> keys = {"type", "tau", "table", "kp", "kd", "qref_deg", "qref", "tau0", "motor"};
        Tab t(table_of(node, path), path, keys);
        cd_actuator_desc a = cd_actuator_desc_default();
        std::vector<double> tt, tv;
        double one = 1.0;
        actuator_law(node, revolute, {}, a, tt, tv, t);
        std::string aname = std::string(m->sys_name[m->body_sys[body]]) + "/" + m->body_name[body];
        a.name = aname.c_str();
        a.ntrn = 1;
        a.trn_body = &body;
        a.trn_ratio = &one;
        int id = cd_model_add_actuator(m.get(), &a, &err);
        if (id < 0) builder_fail(node.loc, path);
        m->body_act[body] = id;
    }

    /* [[actuator]]: one motor driving several joints (a transmission) */
    void transmission_actuator(Node &node, const std::string &path)
    {
        static const std::vector<std::string> keys = {"name", "type", "tau", "table", "kp", "kd", "qref_deg", "qref",
                                                      "tau0", "motor", "joints", "ratios"};
        Tab t(table_of(node, path), path, keys);
        cd_actuator_desc a = cd_actuator_desc_default();
        std::vector<double> tt, tv, ratios;
        std::vector<int> bodies;
        std::string name = name_of_node(t.need("name", "a name"), t.kp("name"));
        if (cd_model_actuator_id(m.get(), name.c_str()) >= 0)
            fail_at(t.get("name")->val->loc, t.kp("name"), "expected an actuator name used once, got '" + name + "' twice");
        const Node &jn = t.need("joints", "an array of \"system/link\" names");
        std::string jp = t.kp("joints");
        if (jn.kind != NK::Array || jn.arr.empty())
            fail_at(jn.loc, jp, "expected a non-empty array of \"system/link\" names, got " + render(jn));
        bool rev = true;
        for (size_t i = 0; i < jn.arr.size(); i++) {
            std::string jname = str_of(*jn.arr[i], idx(jp, i));
            int b = cd_model_body_id(m.get(), jname.c_str());
            if (b < 0 || m->body_parent[b] < 0)
                fail_at(jn.arr[i]->loc, idx(jp, i), "expected the name of a joint (\"system/link\"), got '" + jname + "'");
            for (int o : bodies)
                if (o == b) fail_at(jn.arr[i]->loc, idx(jp, i), "expected each joint once, got '" + jname + "' twice");
            if (m->body_jnt_type[b] != CD_JOINT_REVOLUTE) rev = false;
            bodies.push_back(b);
        }
        if (Entry *e = t.get("ratios")) {
            const Node &rn = *e->val;
            if (rn.kind != NK::Array || rn.arr.size() != bodies.size())
                fail_at(rn.loc, t.kp("ratios"), "expected " + std::to_string(bodies.size()) + " ratios (one per joint), got " + render(rn));
            for (size_t i = 0; i < rn.arr.size(); i++) ratios.push_back(num_of(*rn.arr[i], idx(t.kp("ratios"), i), Range::Any));
        } else {
            ratios.assign(bodies.size(), 1.0);
        }
        actuator_law(node, rev, {"name", "joints", "ratios"}, a, tt, tv, t);
        a.name = name.c_str();
        a.ntrn = (int)bodies.size();
        a.trn_body = bodies.data();
        a.trn_ratio = ratios.data();
        if (cd_model_add_actuator(m.get(), &a, &err) < 0) builder_fail(node.loc, path);
    }

    /* a link's passive elements, stop law and prescribed motion */
    void joint_props(const Tab &t, int id, bool rev, const double *lim)
    {
        cd_joint_props p = cd_joint_props_default();
        bool any = false;
        double sc = rev ? DEG : 1.0;
        if (lim) {
            p.limited = 1;
            p.lower = lim[0] * sc;
            p.upper = lim[1] * sc;
            any = true;
        }
        if (Entry *e = t.get("stop")) {
            std::string sp = t.kp("stop");
            if (!lim) fail_at(e->kloc, sp, std::string("a stop needs the joint's ") + (rev ? "limit_deg" : "limit"));
            Tab st(table_of(*e->val, sp), sp, {"K", "D", "p", "q"});
            p.stop_K = st.num("K", 0.0, Range::Pos);
            p.stop_D = st.num("D", 0.0, Range::NonNeg);
            p.stop_p = st.num("p", 0.0, Range::Ge1);
            p.stop_q = st.num("q", 0.0, Range::Pos);
        }
        if (Entry *e = t.get("spring")) {
            std::string sp = t.kp("spring");
            Tab st(table_of(*e->val, sp), sp, {"stiffness", rev ? "rest_deg" : "rest"});
            p.stiffness = st.need_num("stiffness", Range::NonNeg);
            p.rest = st.num(rev ? "rest_deg" : "rest", 0.0, Range::Any) * sc;
            any = true;
        }
        if (Entry *e = t.get("damping")) {
            p.damping = num_of(*e->val, t.kp("damping"), Range::NonNeg);
            any = true;
        }
        if (Entry *e = t.get("friction")) {
            std::string fp = t.kp("friction");
            Tab ft(table_of(*e->val, fp), fp, {"torque", "stiffness", "damping"});
            p.friction = ft.need_num("torque", Range::Pos);
            p.friction_k = ft.num("stiffness", 0.0, Range::Pos);
            p.friction_d = ft.num("damping", 0.0, Range::NonNeg);
            any = true;
        }
        std::vector<double> pt, pq;
        if (Entry *e = t.get("prescribed")) {
            std::string pp = t.kp("prescribed");
            const char *vk = rev ? "rate_deg_s" : "rate", *qk = rev ? "waypoints_deg" : "waypoints";
            Tab ptab(table_of(*e->val, pp), pp, {"type", vk, "start", qk});
            std::string ty = choice_of(ptab.need("type", "'velocity' or 'waypoints'"), ptab.kp("type"), {"velocity", "waypoints"});
            if (ty == "velocity") {
                if (ptab.get(qk)) fail_at(ptab.get(qk)->kloc, ptab.kp(qk), "does not apply to a 'velocity' profile");
                p.prescribe = CD_PRESCRIBE_VELOCITY;
                p.presc_v = ptab.need_num(vk, Range::Any) * sc;
                p.presc_t0 = ptab.num("start", 0.0, Range::NonNeg);
            } else {
                if (ptab.get(vk)) fail_at(ptab.get(vk)->kloc, ptab.kp(vk), "does not apply to a 'waypoints' profile");
                if (ptab.get("start")) fail_at(ptab.get("start")->kloc, ptab.kp("start"), "does not apply to a 'waypoints' profile");
                rows_of(ptab.need(qk, rev ? "an array of [t, q_deg] rows" : "an array of [t, q] rows"), ptab.kp(qk),
                        rev ? "[t, q_deg]" : "[t, q]", pt, pq);
                for (double &v : pq) v *= sc;
                p.prescribe = CD_PRESCRIBE_WAYPOINTS;
                p.presc_t = pt.data();
                p.presc_q = pq.data();
                p.npresc = (int)pt.size();
            }
            any = true;
        }
        if (any && cd_model_set_joint(m.get(), id, &p, &err) != CD_OK) builder_fail(t.n->loc, t.path);
    }

    void link(Node &node, const std::string &path, SysInfo &s)
    {
        Tab t(&node, path,
              {"name", "parent", "joint", "axis", "origin", "rpy_deg", "quaternion", "mass", "com", "inertia",
               "limit_deg", "limit", "q0_deg", "q0", "qd0_deg_s", "qd0", "checkpoints", "shape", "actuator",
               "stop", "spring", "damping", "friction", "prescribed"});
        std::string name = name_of_node(t.need("name", "a name"), t.kp("name"));
        if (name == "base")
            fail_at(t.get("name")->val->loc, t.kp("name"), "expected a link name other than 'base' (reserved for the base body)");
        if (name == s.name)
            fail_at(t.get("name")->val->loc, t.kp("name"),
                    "expected a link name different from its system's name '" + s.name + "' (the base body has that name)");
        if (s.body_at.count(name))
            fail_at(t.get("name")->val->loc, t.kp("name"),
                    "expected a link name unique in system '" + s.name + "', got '" + name + "' twice");
        cd_link_desc d = cd_link_desc_default();
        d.name = name.c_str();
        d.parent = s.bodies.back().id;  /* default: the previous link, or the base */
        if (Entry *e = t.get("parent")) {
            std::string pn = str_of(*e->val, t.kp("parent"));
            auto it = s.body_at.find(pn);
            if (it == s.body_at.end())
                fail_at(e->val->loc, t.kp("parent"),
                        "expected 'base' or the name of an earlier link of system '" + s.name + "', got '" + pn + "'" +
                            hint(pn, s.body_names()));
            d.parent = s.bodies[it->second].id;
        }
        std::string jt = "revolute";
        if (Entry *e = t.get("joint")) jt = choice_of(*e->val, t.kp("joint"), {"revolute", "prismatic"});
        bool rev = jt == "revolute";
        d.type = rev ? CD_JOINT_REVOLUTE : CD_JOINT_PRISMATIC;
        /* keys of the other joint type: say which one applies */
        struct Alt { const char *bad, *good, *unit; };
        const Alt alts[] = {{"q0", "q0_deg", "deg"}, {"qd0", "qd0_deg_s", "deg/s"}, {"limit", "limit_deg", "deg"}};
        for (const Alt &a : alts) {
            const char *wrong = rev ? a.bad : a.good, *right = rev ? a.good : a.bad;
            if (Entry *e = t.get(wrong))
                fail_at(e->kloc, t.kp(wrong),
                        std::string("does not apply to a ") + jt + " joint (use " + right + " [" +
                            (rev ? a.unit : (std::strcmp(a.good, "qd0_deg_s") == 0 ? "m/s" : "m")) + "])");
        }
        if (Entry *e = t.get("axis")) {
            vec_of(*e->val, t.kp("axis"), 3, d.axis);
            if (!(cd_v3_norm(d.axis) > 1e-12)) fail_at(e->val->loc, t.kp("axis"), "expected a non-zero axis, got " + render(*e->val));
        }
        t.vec("origin", 3, d.pos);
        rotation_of(t, d.rot);
        d.mass = t.need_num("mass", Range::Pos);
        t.vec("com", 3, d.com);
        inertia_of(t.need("inertia", "an inertia (3, 6 or 3x3 numbers)"), t.kp("inertia"), d.inertia);
        const char *q0k = rev ? "q0_deg" : "q0", *qd0k = rev ? "qd0_deg_s" : "qd0", *limk = rev ? "limit_deg" : "limit";
        double sc = rev ? DEG : 1.0;
        double q0u = t.num(q0k, 0.0, Range::Any);
        d.q0 = q0u * sc;
        d.qd0 = t.num(qd0k, 0.0, Range::Any) * sc;
        double lim[2];
        bool has_lim = false;
        if (Entry *e = t.get(limk)) {
            has_lim = true;
            vec_of(*e->val, t.kp(limk), 2, lim, Range::Any, "an array [lower, upper]");
            if (!(lim[0] < lim[1]))
                fail_at(e->val->loc, t.kp(limk), "expected lower < upper, got " + render(*e->val));
            if (q0u < lim[0] || q0u > lim[1])
                fail_at(t.get(q0k) ? t.get(q0k)->val->loc : e->val->loc, t.kp(q0k),
                        "expected an initial position within " + std::string(limk) + " " + render(*e->val) + ", got " +
                            fmt_num(q0u));
            /* enforced as compliant stops (joint_props) */
        }
        int id = cd_model_add_link(m.get(), s.id, &d, &err);
        if (id < 0) body_fail(t, node.loc, path);
        s.add_body(name, id);
        checkpoints(t, s, s.bodies.back());
        shapes(t, s, id);
        if (Entry *e = t.get("actuator")) actuator(*e->val, t.kp("actuator"), id, rev);
        joint_props(t, id, rev, has_lim ? lim : nullptr);
    }

    struct Run {
        std::string title;
        double duration = 0, output_dt = 0, flush_every = 1.0;
        int event_capacity = 4096;
        bool interpolate = false, no_compress = false;
        int hand = -1, object = -1, feature = -1;
        int palm = -1;                 /* the palm body (the hand's base, or the link a gripper is mounted on) */
        bool close_trigger = false;    /* [gripper] close.on = "trigger" */
        std::vector<int> close_act;    /* the gripper's motors and their closing command */
        std::vector<double> close_u;
        std::vector<int> close_finger; /* clutched fingers whose schedule starts at the trigger */
        std::unique_ptr<cd_ctrl_config> control; /* [control] */
        std::vector<double> palm_pos = {0, 0, 0}, palm_rot = {1, 0, 0, 0, 1, 0, 0, 0, 1}; /* palm frame on it */
        double v_max = 1e-3, w_max = 0.05, dwell = 0.2, workspace = 0.0;
        double max_wall_time = 3600.0, max_rhs_evals = 1e9, min_steps = 0, min_rhs_evals = 0;
    };

    /* [gripper] of a mechanism type: the hand (a fixed palm box and fingers
     * of capsule links with check points along them), its drive (actuators
     * or clutched fingers) and the pairs of its check points with every
     * target's shapes, made by cd_build_hand / cd_build_hand_drive
     * (include/capdyn/build.h, src/builders/hand.c) from the cd_hand_desc read
     * here. docs/grippers.md. */
    struct GripState {
        cd_hand_desc h = cd_hand_desc_default();
        cd_hand hand{};
    } grip;

    /* mounted on a link of an existing system (`system`, `attach`): the palm
     * is that link, the fingers become its branches; returns the host or
     * nullptr (a stand-alone hand named `name`) */
    SysInfo *hand_mount(const Tab &t, std::string &name)
    {
        SysInfo *host = nullptr;
        name = "hand";
        if (Entry *g = t.get("system")) {
            std::string gs = str_of(*g->val, t.kp("system"));
            host = find_sys(gs);
            if (!host) fail_at(g->val->loc, t.kp("system"), "expected the name of a system, got '" + gs + "'" + hint(gs, sys_names()));
            if (host->is_target) fail_at(g->val->loc, t.kp("system"), "expected a [[system]] (the chaser), got the target '" + gs + "'");
            if (Entry *e = t.get("name")) fail_at(e->kloc, t.kp("name"), "does not apply to a gripper mounted on a system (the hand is that system)");
            const Node &an = t.need("attach", "the name of the link the palm is mounted on");
            std::string a = str_of(an, t.kp("attach"));
            auto it = host->body_at.find(a);
            if (it == host->body_at.end())
                fail_at(an.loc, t.kp("attach"), "expected 'base' or a link of system '" + gs + "', got '" + a + "'" + hint(a, host->body_names()));
            int attach = host->bodies[it->second].id;
            for (int b = attach + 1; b < m->nbody; b++)
                if (m->body_parent[b] == attach)
                    fail_at(an.loc, t.kp("attach"), "expected a link without child links (the fingers become its only branches), got '" + a + "' (parent of '" + m->body_name[b] + "')");
            for (const char *k : {"palm", "f0_l0"})
                if (host->shape_at.count(k)) fail_at(an.loc, t.kp("attach"), std::string("expected a system without a shape named '") + k + "' (the gripper adds it)");
            name = gs;
            grip.h.attach_body = attach;
        } else if (Entry *e = t.get("attach")) {
            fail_at(e->kloc, t.kp("attach"), "needs 'system' (the system whose link carries the palm)");
        }
        if (Entry *e = t.get("name")) name = name_of_node(*e->val, t.kp("name"));
        if (!host && find_sys(name)) fail_at(t.n->loc, t.kp("name"), "expected a system name not used yet, got '" + name + "'");
        return host;
    }

    /* finger_joint: passive elements of every finger joint (a release
     * spring, a damper, stops) and the initial angles */
    void hand_finger_joint(const Tab &t, cd_hand_desc &h, const Node *&fq0_node, const Node *&flim_node)
    {
        Entry *e = t.get("finger_joint");
        if (!e) return;
        std::string fp = t.kp("finger_joint");
        Tab ft(table_of(*e->val, fp), fp, {"spring", "damping", "limit_deg", "q0_deg", "stop"});
        h.joint_spring = ft.num("spring", 0.0, Range::NonNeg);
        h.joint_damping = ft.num("damping", 0.0, Range::NonNeg);
        if (Entry *l = ft.get("limit_deg")) {
            /* [lower, upper] for every joint, or one such pair per finger link */
            const Node &ln = *l->val;
            std::string lp = ft.kp("limit_deg");
            bool per_link = ln.kind == NK::Array && !ln.arr.empty() && ln.arr[0]->kind == NK::Array;
            std::vector<double> flim;
            for (size_t i = 0; i < (per_link ? ln.arr.size() : 1); i++) {
                double lim[2];
                const Node &pn = per_link ? *ln.arr[i] : ln;
                std::string pp = per_link ? idx(lp, i) : lp;
                vec_of(pn, pp, 2, lim, Range::Any, per_link ? "a pair [lower, upper]" : "an array [lower, upper] or one such pair per finger link");
                if (!(lim[0] < lim[1])) fail_at(pn.loc, pp, "expected lower < upper, got " + render(pn));
                flim.push_back(lim[0] * DEG);
                flim.push_back(lim[1] * DEG);
            }
            if (per_link && flim.size() != 2 * (size_t)h.nlink)
                fail_at(ln.loc, lp, "expected [lower, upper] or " + std::to_string(h.nlink) + " such pairs (one per finger link), got " + render(ln));
            for (int j = 0; j < h.nlink; j++) {
                size_t k = per_link ? 2 * j : 0;
                h.joint_lower[j] = flim[k];
                h.joint_upper[j] = flim[k + 1];
            }
            flim_node = &ln;
            h.joint_limited = 1;
        }
        if (Entry *st_e = ft.get("stop")) {
            /* the stops' law, as a link's `stop` (every finger joint) */
            std::string sp = ft.kp("stop");
            if (!h.joint_limited) fail_at(st_e->kloc, sp, "a stop needs the finger joints' limit_deg");
            Tab st(table_of(*st_e->val, sp), sp, {"K", "D", "p", "q"});
            /* K and D: one number for every link, or one per finger link (base to tip) */
            auto per_link = [&](const char *k, Range r, double *out) {
                Entry *ke = st.get(k);
                if (!ke) return;
                if (ke->val->kind == NK::Array)
                    vec_of(*ke->val, st.kp(k), h.nlink, out, r,
                           ("a number or " + std::to_string(h.nlink) + " numbers (one per finger link)").c_str());
                else
                    for (int j = 0; j < h.nlink; j++) out[j] = num_of(*ke->val, st.kp(k), r);
            };
            per_link("K", Range::Pos, h.joint_stop_K);
            per_link("D", Range::NonNeg, h.joint_stop_D);
            h.joint_stop_p = st.num("p", 0.0, Range::Ge1);
            h.joint_stop_q = st.num("q", 0.0, Range::Pos);
        }
        if (Entry *q = ft.get("q0_deg")) {
            const Node &qn = *q->val;
            if (qn.kind != NK::Array) fail_at(qn.loc, ft.kp("q0_deg"), "expected an array of initial angles [deg], one per finger link, got " + render(qn));
            for (size_t i = 0; i < qn.arr.size(); i++) {
                double v = num_of(*qn.arr[i], idx(ft.kp("q0_deg"), i), Range::Any) * DEG;
                if (i < (size_t)CD_HAND_MAX_LINKS) h.q0[i] = v;
            }
            fq0_node = &qn;
        }
    }

    /* the palm, the links, radii and spacings */
    void hand_geometry(const Tab &t, cd_hand_desc &h, bool mounted)
    {
        if (Entry *e = t.get("palm")) {
            std::string pp = t.kp("palm");
            Tab pt(table_of(*e->val, pp), pp, {"size", "mass", "position", "rpy_deg", "quaternion"});
            pt.vec("size", 3, h.palm_size, Range::Pos);
            if (mounted && pt.get("mass"))
                fail_at(pt.get("mass")->kloc, pt.kp("mass"), "does not apply to a gripper mounted on a link (include the palm's mass in the link's)");
            h.palm_mass = pt.num("mass", h.palm_mass, Range::Pos);
            pt.vec("position", 3, h.palm_pos);
            rotation_of(pt, h.palm_rot);
        }
        const Node &ln = t.need("links", "an array of link lengths [m], base to tip");
        if (ln.kind != NK::Array || ln.arr.empty() || ln.arr.size() > CD_HAND_MAX_LINKS)
            fail_at(ln.loc, t.kp("links"), "expected 1 to 16 link lengths [m], got " + render(ln));
        h.nlink = (int)ln.arr.size();
        for (size_t i = 0; i < ln.arr.size(); i++) h.link_length[i] = num_of(*ln.arr[i], idx(t.kp("links"), i), Range::Pos);
        if (Entry *e = t.get("masses")) {
            if (e->val->kind != NK::Array || e->val->arr.size() != (size_t)h.nlink)
                fail_at(e->val->loc, t.kp("masses"), "expected " + std::to_string(h.nlink) + " masses (one per link), got " + render(*e->val));
            for (int i = 0; i < h.nlink; i++) h.link_mass[i] = num_of(*e->val->arr[i], idx(t.kp("masses"), i), Range::Pos);
        }
        h.radius = t.num("radius", 0.008, Range::Pos);
        h.spacing = t.num("spacing", 0.1, Range::Pos);
        h.checkpoint_spacing = t.num("checkpoint_spacing", h.radius, Range::Pos);
    }

    /* pair_offset; a mounted hand's new links; the initial angles against
     * the stops; the number of check points (bounded before any is made) */
    void hand_checks(const Tab &t, cd_hand_desc &h, SysInfo *host, const Node *fq0_node, const Node *flim_node)
    {
        const double rad = h.radius;
        if (h.layout == CD_HAND_TWO_PAIRS) h.pair_offset = t.num("pair_offset", h.spacing / 2, Range::Pos);
        else if (h.layout == CD_HAND_TWO_INTERLEAVED) {
            /* the two fingers in parallel planes z = -/+ pair_offset: they pass each other */
            h.pair_offset = t.num("pair_offset", 1.5 * rad, Range::Pos);
            if (!(h.pair_offset > rad)) fail_at(t.get("pair_offset")->val->loc, t.kp("pair_offset"), "expected more than the finger radius " + fmt_num(rad) + " m (the fingers must pass each other), got " + fmt_num(h.pair_offset));
        } else if (Entry *e = t.get("pair_offset")) fail_at(e->kloc, t.kp("pair_offset"), "applies to hand = 'two_pairs' or 'two_interleaved' only");
        int nf = h.layout == CD_HAND_TWO_OPPOSED || h.layout == CD_HAND_TWO_INTERLEAVED ? 2 : h.layout == CD_HAND_THREE_120 ? 3 : 4;
        for (int f = 0; f < nf; f++)
            for (int j = 0; j < h.nlink; j++) {
                std::string ln = "f" + std::to_string(f) + "_l" + std::to_string(j);
                if (host && host->body_at.count(ln)) fail_at(t.n->loc, t.path, "expected a system without a link named '" + ln + "' (the gripper adds it)");
                if (fq0_node && (size_t)h.nlink != fq0_node->arr.size())
                    fail_at(fq0_node->loc, t.kp("finger_joint") + ".q0_deg", "expected " + std::to_string(h.nlink) + " angles (one per finger link), got " + render(*fq0_node));
                if (flim_node && (h.q0[j] < h.joint_lower[j] - 1e-12 || h.q0[j] > h.joint_upper[j] + 1e-12))
                    fail_at(fq0_node ? fq0_node->loc : flim_node->loc, t.kp("finger_joint") + (fq0_node ? ".q0_deg" : ".limit_deg"),
                            std::string("expected initial angles within limit_deg (") + (fq0_node ? "" : "q0_deg defaults to 0, ") + "link " + std::to_string(j) + ": " +
                                fmt_num(h.q0[j] / DEG) + " deg, stops [" + fmt_num(h.joint_lower[j] / DEG) + ", " + fmt_num(h.joint_upper[j] / DEG) + "]), got " +
                                render(fq0_node ? *fq0_node : *flim_node));
            }
        hand_bounds(t, h);
    }

    /* a hand's check points: at most CD_HAND_MAX_CHECKPOINTS, counted before
     * they are made, and at least one on each finger link */
    void hand_bounds(const Tab &t, const cd_hand_desc &h)
    {
        const double cps = h.checkpoint_spacing;
        double lmax = 0;
        int jshort = -1;
        for (int j = 0; j < h.nlink; j++) {
            lmax = std::max(lmax, h.link_length[j]);
            if (jshort < 0 && !(cps <= h.link_length[j] + 1e-12)) jshort = j;
        }
        /* the key that sets the spacing: checkpoint_spacing, else radius (its default) */
        const char *key = t.get("checkpoint_spacing") ? "checkpoint_spacing" : t.get("radius") ? "radius" : nullptr;
        double n = cd_hand_checkpoint_count(&h);
        if (!(n <= CD_HAND_MAX_CHECKPOINTS)) {
            double palm = (h.layout == CD_HAND_TWO_PAIRS ? 2 : 1) * std::max(0.0, std::floor((h.spacing - 2 * cps + 1e-12) / cps) + 1);
            if (!key) key = palm > n - palm ? "spacing" : "links";
            Entry *e = t.get(key);
            char nb[32];
            std::snprintf(nb, sizeof nb, "%.3g", n);
            fail_at(e ? e->val->loc : t.n->loc, t.kp(key),
                    "expected a hand with at most " + std::to_string(CD_HAND_MAX_CHECKPOINTS) + " check points (palm and fingers), got " +
                        nb + " (checkpoint_spacing = " + fmt_num(cps) + " m along links of up to " + fmt_num(lmax) +
                        " m and a palm row of " + fmt_num(h.spacing) + " m); raise checkpoint_spacing or shorten the hand");
        }
        if (jshort >= 0) {
            if (!key) key = "links";
            Entry *e = t.get(key);
            fail_at(e ? e->val->loc : t.n->loc, t.kp(key),
                    "expected a checkpoint_spacing no longer than every finger link, got " + fmt_num(cps) + " m: link " +
                        std::to_string(jshort) + " (" + fmt_num(h.link_length[jshort]) +
                        " m) would have no check point and pass through objects");
        }
    }

    /* stage 1: the palm and the fingers (a mounted gripper's fingers are
     * links of its system: built right after that system's links, before
     * the next system) */
    void hand_stage1(const Tab &t, const std::string &ty, Run &run)
    {
        cd_hand_desc &h = grip.h;
        h.type = ty == "soft" ? CD_HAND_SOFT : ty == "tako" ? CD_HAND_TAKO : ty == "space" ? CD_HAND_SPACE : CD_HAND_TORQUE_SWITCH;
        std::string name;
        SysInfo *host = hand_mount(t, name);
        std::string preset = "two_opposed";
        if (Entry *e = t.get("hand")) preset = choice_of(*e->val, t.kp("hand"), {"two_opposed", "three_120", "two_pairs", "two_interleaved"});
        h.layout = preset == "two_opposed" ? CD_HAND_TWO_OPPOSED : preset == "three_120" ? CD_HAND_THREE_120
                 : preset == "two_pairs" ? CD_HAND_TWO_PAIRS : CD_HAND_TWO_INTERLEAVED;
        hand_geometry(t, h, host != nullptr);
        const Node *fq0_node = nullptr, *flim_node = nullptr;
        hand_finger_joint(t, h, fq0_node, flim_node);
        /* the palm frame on its body (mounted) or the hand's fixed base at palm.position */
        double pbpos[3] = {0, 0, 0};
        if (host) cd_v3_copy(pbpos, h.palm_pos);
        run.palm_rot.assign(h.palm_rot, h.palm_rot + 9);
        run.palm_pos.assign(pbpos, pbpos + 3);
        hand_checks(t, h, host, fq0_node, flim_node);
        h.name = name.c_str();
        int ncp0 = m->ncp, nshape0 = m->nshape, nbody0 = m->nbody;
        if (cd_build_hand(m.get(), &h, &grip.hand, &err) < 0) builder_fail(t.n->loc, t.path);
        h.name = nullptr;
        /* the loader's names of what the builder made */
        SysInfo Snew;
        SysInfo &S = host ? *host : Snew;
        if (!host) {
            S.name = name;
            S.loc = t.n->loc;
            S.path = t.path;
            S.id = grip.hand.sys;
            S.add_body("base", m->sys_body_adr[S.id]);
        }
        for (int b = nbody0; b < m->nbody; b++) S.add_body(m->body_name[b], b);
        for (int k = nshape0; k < m->nshape; k++) {
            std::string sn = k == grip.hand.palm_shape ? "palm" : m->body_name[m->shape_body[k]];
            S.shape_at.emplace(sn, S.shapes.size());
            S.shapes.push_back({sn, k});
        }
        for (int c = ncp0; c < m->ncp; c++) {
            for (auto &bi : S.bodies)
                if (bi.id == m->cp_body[c]) bi.ncp++;
            S.ncp++;
        }
        if (!host) {
            sys_at.emplace(S.name, sys.size());
            sys.push_back(S);
        }
        run.palm = grip.hand.palm;
        run.hand = grip.hand.sys;
    }

    /* stage 2: the drive and the contact pairs (after every system) */
    void hand_stage2(const Tab &t, const std::string &ty, const LawState &def, Run &run)
    {
        cd_hand_desc &h = grip.h;
        h.torque = t.num("torque", 0.2, Range::Any);
        h.open_at = t.num("open_at", 0.0, Range::NonNeg);
        if (Entry *e = t.get("close")) {
            std::string cp = t.kp("close");
            Tab ct(table_of(*e->val, cp), cp, {"time", "angle_deg", "start", "on"});
            if (Entry *o = ct.get("on")) run.close_trigger = choice_of(*o->val, ct.kp("on"), {"time", "trigger"}) == "trigger";
            if (run.close_trigger && ct.get("start")) fail_at(ct.get("start")->kloc, ct.kp("start"), "does not apply with on = 'trigger' (the [control] grasp trigger starts the closing)");
            if (run.close_trigger && h.open_at > 0) fail_at(t.get("open_at")->kloc, t.kp("open_at"), "does not apply with close.on = 'trigger'");
            h.close_time = ct.num("time", h.close_time, Range::Pos);
            h.close_angle = ct.num("angle_deg", 120.0, Range::Pos) * DEG;
            h.close_start = ct.num("start", 0.0, Range::NonNeg);
        }
        h.close_on_trigger = run.close_trigger ? 1 : 0;
        if (h.open_at > 0 && h.open_at <= h.close_start + h.close_time)
            fail_at(t.get("open_at")->val->loc, t.kp("open_at"), "expected open_at after the closing ends (" + fmt_num(h.close_start + h.close_time) + " s)");
        if (Entry *e = t.get("ratios")) {
            if (e->val->kind != NK::Array || e->val->arr.size() != (size_t)h.nlink)
                fail_at(e->val->loc, t.kp("ratios"), "expected " + std::to_string(h.nlink) + " ratios (base to tip), got " + render(*e->val));
            for (int i = 0; i < h.nlink; i++) h.ratio[i] = num_of(*e->val->arr[i], idx(t.kp("ratios"), i), Range::Pos);
        }
        if (Entry *e = t.get("motor")) {
            std::string mp = t.kp("motor");
            Tab mt(table_of(*e->val, mp), mp, {"stall_torque", "noload_speed"});
            h.stall_torque = mt.need_num("stall_torque", Range::Pos);
            h.noload_speed = mt.need_num("noload_speed", Range::Pos);
        }
        if (ty == "soft" || ty == "tako") {
            if (t.get("clutch")) fail_at(t.get("clutch")->kloc, t.kp("clutch"), "applies to 'space' and 'torque_switch' grippers only");
        } else if (Entry *e = t.get("clutch")) {
            std::string cp = t.kp("clutch");
            Tab ct(table_of(*e->val, cp), cp, {"threshold", "wire_stiffness", "wire_damping", "torque_limit"});
            h.clutch_threshold = ct.num("threshold", h.clutch_threshold, Range::Pos);
            h.wire_stiffness = ct.num("wire_stiffness", h.wire_stiffness, Range::Pos);
            h.wire_damping = ct.num("wire_damping", -1, Range::NonNeg);
            h.torque_limit = ct.num("torque_limit", 0.0, Range::NonNeg);
        }
        if (ty != "soft" && ty != "tako") {
            /* the clutch disengages when the coupling torque reaches the
             * threshold; a coupling limited below it never lets it fire */
            Entry *ce = t.get("clutch");
            Entry *le = ce && ce->val->kind == NK::Table ? ce->val->find("torque_limit") : nullptr;
            if (h.torque_limit > 0 && !(h.torque_limit > h.clutch_threshold))
                fail_at(le ? le->val->loc : t.n->loc, t.kp("clutch") + ".torque_limit",
                        "expected 0 (the motor's stall torque) or a value in (clutch.threshold, inf) = (" +
                            fmt_num(h.clutch_threshold) + ", inf) N m (a coupling limited below the threshold never disengages the clutch), got " +
                            fmt_num(h.torque_limit));
            if (h.torque_limit == 0 && h.stall_torque > 0 && !(h.stall_torque > h.clutch_threshold)) {
                Entry *me = t.get("motor");
                Entry *se = me && me->val->kind == NK::Table ? me->val->find("stall_torque") : nullptr;
                fail_at(se ? se->val->loc : t.n->loc, t.kp("motor") + ".stall_torque",
                        "expected a value in (clutch.threshold, inf) = (" + fmt_num(h.clutch_threshold) +
                            ", inf) N m without clutch.torque_limit (the stall torque limits the coupling, and one below the threshold never disengages the clutch), got " +
                            fmt_num(h.stall_torque));
            }
        }
        std::vector<int> targets;
        for (auto &s2 : sys)
            if (s2.is_target) targets.push_back(s2.id);
        int pair0 = m->npair;
        if (cd_build_hand_drive(m.get(), &h, &grip.hand, &def.law, targets.data(), (int)targets.size(), &err) != CD_OK)
            builder_fail(t.n->loc, t.path);
        /* finger_contact: the law of the finger-on-finger pairs (a finger's
         * check points against another finger's link of this hand), on top
         * of [contact]; the pairs against the targets keep [contact]'s law.
         * A [[pair]] cannot set it: the hand's pairs come first and a later
         * pair repeating a slot does not change its law. */
        if (Entry *e = t.get("finger_contact")) {
            std::string fp = t.kp("finger_contact");
            Tab ft(table_of(*e->val, fp), fp, LAW_KEYS);
            LawState ls = law(ft, def);
            int lid = cd_model_add_law(m.get(), &ls.law, &err), nff = 0;
            if (lid < 0) builder_fail(e->val->loc, fp);
            for (int p = pair0; p < m->npair; p++)
                if (m->pair_body[p] >= 0 && m->pair_sys[p] == grip.hand.sys && m->body_sys[m->shape_body[m->pair_shape[p]]] == grip.hand.sys) {
                    m->pair_law[p] = lid;
                    nff++;
                }
            if (nff == 0)
                fail_at(e->kloc, fp, "does not apply to this hand: its fingers cannot touch each other (no finger-on-finger pairs)");
        }
        for (int k = 0; k < grip.hand.nact; k++) {
            run.close_act.push_back(grip.hand.act[k]);
            run.close_u.push_back(grip.hand.act_close_u[k]);
        }
        if (run.close_trigger)
            for (int k = 0; k < grip.hand.nclutch; k++) run.close_finger.push_back(grip.hand.clutch[k]); /* its schedule starts at the trigger */
    }

    /* stage 1, stage 2 or 0: both */
    void gripper_hand(const Tab &t, const std::string &ty, const LawState &def, Run &run, int stage = 0)
    {
        if (stage != 2) hand_stage1(t, ty, run);
        if (stage != 1) hand_stage2(t, ty, def, run);
    }
    /* [control]: the built-in capture controller (control.h, docs/capture.md) */
    void control(Entry &e, Run &run)
    {
        Tab t(table_of(*e.val, "control"), "control",
              {"type", "system", "fixture", "grasp_point", "grasp_rpy_deg", "approach_axis", "lateral_tol", "kp_pos",
               "kp_rot", "v_max", "w_max", "dls", "qd_max_deg_s", "rate_gain", "tau_max", "trigger_distance",
               "close_time", "impedance", "detumble", "attitude", "misalign", "start"});
        choice_of(t.need("type", "'capture'"), t.kp("type"), {"capture"});
        std::unique_ptr<cd_ctrl_config> c(new cd_ctrl_config(cd_ctrl_config_default()));
        /* the chaser: the gripper's system by default */
        if (Entry *g = t.get("system")) {
            std::string gs = str_of(*g->val, t.kp("system"));
            SysInfo *s = find_sys(gs);
            if (!s) fail_at(g->val->loc, t.kp("system"), "expected the name of a system, got '" + gs + "'" + hint(gs, sys_names()));
            c->sys = s->id;
        } else if (run.palm >= 0 && m->body_sys[run.palm] == run.hand) {
            c->sys = run.hand;
        } else {
            t.need("system", "the chaser's name (or a [gripper] mounted with system/attach)");
        }
        if (m->sys_base_type[c->sys] != CD_BASE_FREE)
            fail_at(t.n->loc, t.kp("system"), std::string("expected a free-floating chaser, got '") + m->sys_name[c->sys] + "' (fixed base)");
        if (!(run.hand == c->sys && run.palm >= 0 && run.palm != m->sys_body_adr[c->sys]))
            fail_at(t.n->loc, t.path, std::string("expected a [gripper] mounted on a link of '") + m->sys_name[c->sys] + "' (system, attach): the controller moves its palm");
        c->palm = run.palm;
        for (int k = 0; k < 3; k++) c->palm_pos[k] = run.palm_pos[k];
        for (int k = 0; k < 9; k++) c->palm_rot[k] = run.palm_rot[k];
        /* the fixture: a shape "system/shape" */
        {
            const Node &fn = t.need("fixture", "a shape \"system/shape\" of the target (its centre and frame)");
            std::string f = str_of(fn, t.kp("fixture"));
            size_t sl = f.find('/');
            SysInfo *s = sl == std::string::npos ? nullptr : find_sys(f.substr(0, sl));
            if (!s || !s->shape_at.count(f.substr(sl + 1)))
                fail_at(fn.loc, t.kp("fixture"), "expected a shape \"system/shape\" of another system, got '" + f + "'");
            if (s->id == c->sys) fail_at(fn.loc, t.kp("fixture"), "expected a shape of another system than the chaser, got '" + f + "'");
            int sh = s->shapes[s->shape_at[f.substr(sl + 1)]].second;
            c->fixture_body = m->shape_body[sh];
            for (int k = 0; k < 3; k++) c->fixture_pos[k] = m->shape_pos[3 * sh + k];
            for (int k = 0; k < 9; k++) c->fixture_rot[k] = m->shape_rot[9 * sh + k];
        }
        t.vec("grasp_point", 3, c->grasp_point);
        if (Entry *g = t.get("grasp_rpy_deg")) {
            double r[3];
            vec_of(*g->val, t.kp("grasp_rpy_deg"), 3, r);
            cd_m3_from_rpy(c->grasp_rot, r[0] * DEG, r[1] * DEG, r[2] * DEG);
        }
        if (Entry *g = t.get("approach_axis")) {
            vec_of(*g->val, t.kp("approach_axis"), 3, c->approach_axis);
            if (!(cd_v3_norm(c->approach_axis) > 1e-12)) fail_at(g->val->loc, t.kp("approach_axis"), "expected a non-zero vector, got " + render(*g->val));
        }
        c->lateral_tol = t.num("lateral_tol", c->lateral_tol, Range::Pos);
        c->kp_pos = t.num("kp_pos", c->kp_pos, Range::NonNeg);
        c->kp_rot = t.num("kp_rot", c->kp_rot, Range::NonNeg);
        c->v_max = t.num("v_max", c->v_max, Range::Pos);
        c->w_max = t.num("w_max", c->w_max, Range::Pos);
        c->dls = t.num("dls", c->dls, Range::Pos);
        c->qd_max = t.num("qd_max_deg_s", c->qd_max / DEG, Range::Pos) * DEG;
        c->rate_gain = t.num("rate_gain", c->rate_gain, Range::Pos);
        c->tau_max = t.num("tau_max", c->tau_max, Range::NonNeg);
        c->trigger_distance = t.num("trigger_distance", c->trigger_distance, Range::Pos);
        c->close_time = t.num("close_time", c->close_time, Range::NonNeg);
        if (Entry *g = t.get("start")) c->start_hold = choice_of(*g->val, t.kp("start"), {"approach", "hold"}) == "hold";
        if (Entry *g = t.get("impedance")) {
            std::string ip = t.kp("impedance");
            Tab it(table_of(*g->val, ip), ip, {"frequency", "damping_ratio"});
            c->imp_wn = it.num("frequency", c->imp_wn, Range::NonNeg);
            c->imp_zeta = it.num("damping_ratio", c->imp_zeta, Range::NonNeg);
        }
        if (Entry *g = t.get("detumble")) {
            std::string dp = t.kp("detumble");
            Tab dt(table_of(*g->val, dp), dp, {"on", "after", "gain", "force_max", "moment_max", "base"});
            c->detumble = dt.get("on") ? (bool_of(*dt.get("on")->val, dt.kp("on")) ? 1 : 0) : 1;
            c->detumble_after = dt.num("after", c->detumble_after, Range::NonNeg);
            c->detumble_gain = dt.num("gain", c->detumble_gain, Range::Pos);
            c->detumble_f_max = dt.num("force_max", c->detumble_f_max, Range::Pos);
            dt.vec("moment_max", 3, c->detumble_n_max, Range::Pos);
            if (Entry *b = dt.get("base"))
                c->detumble_base = choice_of(*b->val, dt.kp("base"), {"damp", "attitude"}) == "damp";
        }
        if (Entry *g = t.get("attitude")) {
            std::string ap = t.kp("attitude");
            Tab at(table_of(*g->val, ap), ap, {"on", "kp", "kd", "tau_max"});
            c->attitude = at.get("on") ? (bool_of(*at.get("on")->val, at.kp("on")) ? 1 : 0) : 1;
            c->att_kp = at.num("kp", c->att_kp, Range::NonNeg);
            c->att_kd = at.num("kd", c->att_kd, Range::NonNeg);
            c->att_tau_max = at.num("tau_max", c->att_tau_max, Range::Pos);
        }
        /* misalignment of the approach: an aim error (position in the palm
         * frame, orientation) and a velocity error of the target */
        if (Entry *g = t.get("misalign")) {
            std::string mp = t.kp("misalign");
            Tab mt(table_of(*g->val, mp), mp, {"position", "rpy_deg", "velocity"});
            double dp[3] = {0, 0, 0}, r[3] = {0, 0, 0}, dv[3] = {0, 0, 0}, Re[9], G[9];
            mt.vec("position", 3, dp);
            mt.vec("rpy_deg", 3, r);
            mt.vec("velocity", 3, dv);
            cd_v3_add(c->grasp_point, c->grasp_point, dp);
            cd_m3_from_rpy(Re, r[0] * DEG, r[1] * DEG, r[2] * DEG);
            cd_m3_mul(G, c->grasp_rot, Re);
            cd_m3_copy(c->grasp_rot, G);
            int ts = m->body_sys[c->fixture_body];
            if (m->sys_base_type[ts] == CD_BASE_FREE) cd_v3_add(m->sys_vel0 + 3 * ts, m->sys_vel0 + 3 * ts, dv);
        }
        if (run.close_trigger) {
            if (run.close_act.size() > CD_CTRL_MAX_ACT) fail_at(t.n->loc, t.path, "expected at most " + std::to_string(CD_CTRL_MAX_ACT) + " gripper motors");
            c->nclose = (int)run.close_act.size();
            for (size_t k = 0; k < run.close_act.size(); k++) { c->close_act[k] = run.close_act[k]; c->close_u[k] = run.close_u[k]; }
            if (run.close_finger.size() > CD_CTRL_MAX_ACT) fail_at(t.n->loc, t.path, "expected at most " + std::to_string(CD_CTRL_MAX_ACT) + " clutched fingers");
            c->nclose_finger = (int)run.close_finger.size();
            for (size_t k = 0; k < run.close_finger.size(); k++) c->close_finger[k] = run.close_finger[k];
        }
        c->user_switch0 = m->nuser;
        if (cd_model_set_user_switches(m.get(), m->nuser + (c->detumble ? 3 : 2), &err) != CD_OK) builder_fail(t.n->loc, t.path);
        run.control = std::move(c);
    }

    /* [[system]] urdf = "file.urdf" (docs/urdf.md): the system from a URDF
     * file (src/io/urdf.cpp), then overrides by joint name in [[system.joint]] */
    std::vector<std::pair<std::shared_ptr<cd_urdf>, int>> urdfs;
    std::string warnings;
    void system_urdf(Node &node, const std::string &path)
    {
        Tab t(&node, path,
              {"name", "urdf", "base", "position", "rpy_deg", "quaternion", "velocity", "angular_velocity",
               "angular_velocity_deg_s", "prescribed_motion", "ignore_limits", "checkpoint_spacing", "checkpoint_radius", "joint"});
        Entry *ue = t.get("urdf");
        std::string file = str_of(*ue->val, t.kp("urdf"));
        std::filesystem::path fp(file);
        if (fp.is_relative() && ue->val->loc.file && !ue->val->loc.ovr)
            fp = std::filesystem::path(*ue->val->loc.file).parent_path() / fp;
        cd_error uerr{};
        std::shared_ptr<cd_urdf> u(cd_urdf_read(fp.string().c_str(), &uerr), cd_urdf_free);
        if (!u) fail_at(ue->val->loc, t.kp("urdf"), uerr.msg, uerr.status == CD_EIO ? CD_EIO : CD_EINVAL);
        warnings += cd_urdf_warnings(u.get());
        SysInfo s;
        s.name = t.get("name") ? name_of_node(*t.get("name")->val, t.kp("name")) : std::string(cd_urdf_robot_name(u.get()));
        s.loc = node.loc;
        s.path = path;
        if (find_sys(s.name))
            fail_at(t.get("name") ? t.get("name")->val->loc : node.loc, t.kp("name"),
                    "expected a system name unique in the scenario (systems and targets), got '" + s.name + "' twice");
        cd_urdf_opts o = cd_urdf_opts_default();
        o.name = s.name.c_str();
        if (Entry *e = t.get("base")) o.fixed = choice_of(*e->val, t.kp("base"), {"free", "fixed"}) == "fixed";
        t.vec("position", 3, o.pos);
        double R[9];
        rotation_of(t, R);
        if (Entry *e = t.get("quaternion")) vec_of(*e->val, t.kp("quaternion"), 4, o.quat);
        else cd_m3_to_quat(o.quat, R);
        Entry *w = t.get("angular_velocity"), *wd = t.get("angular_velocity_deg_s");
        if (w && wd) fail_at(wd->kloc, t.kp("angular_velocity_deg_s"), "give either angular_velocity [rad/s] or angular_velocity_deg_s, not both");
        if (o.fixed)
            for (const char *k : {"velocity", "angular_velocity", "angular_velocity_deg_s", "prescribed_motion"})
                if (Entry *e = t.get(k)) fail_at(e->kloc, t.kp(k), "applies only to a free base (this system has base = \"fixed\")");
        t.vec("velocity", 3, o.vel);
        if (w) vec_of(*w->val, t.kp("angular_velocity"), 3, o.angvel);
        if (wd) {
            vec_of(*wd->val, t.kp("angular_velocity_deg_s"), 3, o.angvel);
            for (double &v : o.angvel) v *= DEG;
        }
        if (Entry *e = t.get("ignore_limits")) o.ignore_limits = bool_of(*e->val, t.kp("ignore_limits")) ? 1 : 0;
        o.checkpoint_spacing = t.num("checkpoint_spacing", 0.0, Range::NonNeg);
        o.checkpoint_radius = t.num("checkpoint_radius", 0.0, Range::NonNeg);
        /* [[system.joint]]: name first (q0 is needed when the link is made) */
        std::vector<Node *> jt;
        std::vector<std::string> jpath, jname;
        std::vector<const char *> q0n;
        std::vector<double> q0v;
        if (Entry *e = t.get("joint")) {
            std::string p = t.kp("joint");
            auto v = tables_of(*e->val, p, "[[system.joint]]");
            for (size_t i = 0; i < v.size(); i++) {
                jt.push_back(v[i]);
                jpath.push_back(e->val->kind == NK::Array ? idx(p, i) : p);
            }
        }
        jname.reserve(jt.size());  /* q0n points into it: no reallocation */
        for (size_t i = 0; i < jt.size(); i++) {
            Tab j(jt[i], jpath[i], {"name", "q0_deg", "q0", "limit_deg", "limit", "stop", "spring", "damping", "friction", "actuator", "prescribed"});
            const Node &nn = j.need("name", "the name of a joint of the URDF");
            jname.push_back(str_of(nn, j.kp("name")));
            for (size_t k = 0; k < i; k++)
                if (jname[k] == jname[i]) fail_at(nn.loc, j.kp("name"), "expected each joint once, got '" + jname[i] + "' twice");
            int ji = cd_urdf_joint_index(u.get(), jname[i].c_str());
            if (ji == -2) fail_at(nn.loc, j.kp("name"), "expected a moving joint, got '" + jname[i] + "' (a fixed joint: its link is merged into its parent)");
            if (ji < 0) fail_at(nn.loc, j.kp("name"), "expected the name of a joint of '" + fp.string() + "', got '" + jname[i] + "'");
            for (const char *k : {"q0_deg", "q0"})
                if (Entry *qe = j.get(k)) {
                    q0n.push_back(jname[i].c_str());
                    q0v.push_back(num_of(*qe->val, j.kp(k), Range::Any) * (k[2] == '_' ? DEG : 1.0));
                }
        }
        o.q0_joint = q0n.data();
        o.q0 = q0v.data();
        o.nq0 = (int)q0n.size();
        s.id = cd_urdf_build(u.get(), m.get(), &o, &err);
        if (s.id < 0) builder_fail(ue->val->loc, t.kp("urdf"));
        for (int b = 0; b < m->sys_nbody[s.id]; b++) {
            int id = m->sys_body_adr[s.id] + b;
            s.add_body(b == 0 ? "base" : m->body_name[id], id);
        }
        for (int k = 0, sh0 = m->nshape - cd_urdf_nshape(u.get()); k < cd_urdf_nshape(u.get()); k++) {
            s.shape_at.emplace(cd_urdf_shape_name(u.get(), k), s.shapes.size());
            s.shapes.push_back({cd_urdf_shape_name(u.get(), k), sh0 + k});
        }
        if (Entry *e = t.get("prescribed_motion"))
            if (bool_of(*e->val, t.kp("prescribed_motion")) && cd_model_prescribe_base(m.get(), s.id, o.vel, o.angvel, &err) != CD_OK)
                builder_fail(e->val->loc, t.kp("prescribed_motion"));
        /* the overrides, by joint name */
        for (size_t i = 0; i < jt.size(); i++) {
            Tab j(jt[i], jpath[i], {"name", "q0_deg", "q0", "limit_deg", "limit", "stop", "spring", "damping", "friction", "actuator", "prescribed"});
            int id = cd_urdf_joint_body(u.get(), m.get(), s.id, jname[i].c_str());  /* checked above: a moving joint */
            bool rev = m->body_jnt_type[id] == CD_JOINT_REVOLUTE;
            const char *wq = rev ? "q0" : "q0_deg", *wl = rev ? "limit" : "limit_deg";
            for (const char *k : {wq, wl})
                if (Entry *e = j.get(k)) fail_at(e->kloc, j.kp(k), std::string("does not apply to a ") + (rev ? "revolute" : "prismatic") + " joint");
            double lim[2];
            const double *lp = nullptr;
            const char *limk = rev ? "limit_deg" : "limit";
            double sc = rev ? DEG : 1.0;
            if (Entry *e = j.get(limk)) {
                vec_of(*e->val, j.kp(limk), 2, lim, Range::Any, "an array [lower, upper]");
                if (!(lim[0] < lim[1])) fail_at(e->val->loc, j.kp(limk), "expected lower < upper, got " + render(*e->val));
                lp = lim;
            } else if (m->body_lim_id[id] >= 0) {
                lim[0] = m->body_limit[6 * id] / sc;
                lim[1] = m->body_limit[6 * id + 1] / sc;
                lp = lim;
            }
            bool props = false;
            for (const char *k : {"limit_deg", "limit", "stop", "spring", "damping", "friction", "prescribed"}) props = props || j.get(k);
            if (props) joint_props(j, id, rev, lp);
            if (Entry *e = j.get("actuator")) actuator(*e->val, j.kp("actuator"), id, rev);
        }
        sys_at.emplace(s.name, sys.size());
        sys.push_back(s);
        urdfs.emplace_back(u, s.id);
    }

    /* [[system]] (is_target = false) or the [[target]] sugar */
    void system(Node &node, const std::string &path, bool is_target)
    {
        if (!is_target && node.kind == NK::Table && node.find("urdf")) {
            system_urdf(node, path);
            return;
        }
        std::vector<std::string> keys = {"name",        "mass",     "inertia",          "position",
                                         "rpy_deg",     "quaternion", "velocity",       "angular_velocity",
                                         "angular_velocity_deg_s", "checkpoints", "shape", "prescribed_motion"};
        if (!is_target) {
            keys.push_back("base");
            keys.push_back("link");
        } else {
            keys.push_back("frame");
        }
        Tab t(&node, path, keys);
        SysInfo s;
        s.is_target = is_target;
        s.name = name_of_node(t.need("name", "a name"), t.kp("name"));
        s.loc = node.loc;
        s.path = path;
        if (find_sys(s.name))
            fail_at(t.get("name")->val->loc, t.kp("name"),
                    "expected a system name unique in the scenario (systems and targets), got '" + s.name + "' twice");
        cd_system_desc d = cd_system_desc_default();
        d.name = s.name.c_str();
        bool fixed = false;
        if (Entry *e = t.get("base")) fixed = choice_of(*e->val, t.kp("base"), {"free", "fixed"}) == "fixed";
        d.type = fixed ? CD_BASE_FIXED : CD_BASE_FREE;
        if (fixed) {
            d.mass = t.num("mass", 1.0, Range::Pos);
            if (Entry *e = t.get("inertia")) inertia_of(*e->val, t.kp("inertia"), d.inertia);
        } else {
            d.mass = t.need_num("mass", Range::Pos);
            inertia_of(t.need("inertia", "an inertia (3, 6 or 3x3 numbers)"), t.kp("inertia"), d.inertia);
        }
        t.vec("position", 3, d.pos);
        double R[9];
        rotation_of(t, R);
        if (Entry *e = t.get("quaternion")) {
            vec_of(*e->val, t.kp("quaternion"), 4, d.quat);  /* kept as given (normalised by the builder) */
        } else {
            cd_m3_to_quat(d.quat, R);
        }
        Entry *w = t.get("angular_velocity"), *wd = t.get("angular_velocity_deg_s");
        if (w && wd)
            fail_at(wd->kloc, t.kp("angular_velocity_deg_s"), "give either angular_velocity [rad/s] or angular_velocity_deg_s, not both");
        if (fixed)
            for (const char *k : {"velocity", "angular_velocity", "angular_velocity_deg_s"})
                if (Entry *e = t.get(k))
                    fail_at(e->kloc, t.kp(k), "applies only to a free base (this system has base = \"fixed\")");
        t.vec("velocity", 3, d.vel);
        if (w) vec_of(*w->val, t.kp("angular_velocity"), 3, d.angvel);
        if (wd) {
            vec_of(*wd->val, t.kp("angular_velocity_deg_s"), 3, d.angvel);
            for (double &v : d.angvel) v *= DEG;
        }
        s.id = cd_model_add_system(m.get(), &d, &err);
        if (s.id < 0) body_fail(t, node.loc, path);
        if (Entry *e = t.get("prescribed_motion")) {
            if (fixed) fail_at(e->kloc, t.kp("prescribed_motion"), "applies only to a free base (this system has base = \"fixed\")");
            if (bool_of(*e->val, t.kp("prescribed_motion")) && cd_model_prescribe_base(m.get(), s.id, d.vel, d.angvel, &err) != CD_OK)
                builder_fail(e->val->loc, t.kp("prescribed_motion"));
        }
        s.add_body("base", m->sys_body_adr[s.id]);
        if (Entry *e = is_target ? t.get("frame") : nullptr) {
            s.in_palm = choice_of(*e->val, t.kp("frame"), {"world", "palm"}) == "palm";
            s.frame_loc = e->kloc;
        }
        sys_at.emplace(s.name, sys.size());
        sys.push_back(s);
        SysInfo &S = sys.back();
        checkpoints(t, S, S.bodies[0]);
        if (is_target) {
            Entry *e = t.get("shape");
            if (!e) t.need("shape", "a table {type = ..., sizes}, or an array of them");
            if (e->val->kind == NK::Array) { /* a composite object: several shapes, each named */
                auto v = tables_of(*e->val, t.kp("shape"), "shape = [{...}, ...]");
                for (size_t i = 0; i < v.size(); i++) shape(*v[i], idx(t.kp("shape"), i), S, S.bodies[0].id, nullptr);
            } else {
                shape(*table_of(*e->val, t.kp("shape")), t.kp("shape"), S, S.bodies[0].id, "shape");
            }
        } else {
            shapes(t, S, S.bodies[0].id);
            if (Entry *e = t.get("link")) {
                std::string p = t.kp("link");
                auto links = tables_of(*e->val, p, "[[system.link]]");
                for (size_t i = 0; i < links.size(); i++)
                    link(*links[i], e->val->kind == NK::Array ? idx(p, i) : p, S);
            }
        }
    }

    /* The contact law of one level ([contact] or a [[pair]]) on top of `in`. */
    LawState law(const Tab &t, const LawState &in)
    {
        LawState s = in;
        cd_contact_law &l = s.law;
        Entry *rule = t.get("rule"), *K = t.get("K"), *D = t.get("D");
        if (rule && (K || D)) {
            Entry *e = K ? K : D;
            fail_at(e->kloc, t.kp(e->key.c_str()), "K and D are computed from the 'rule' table here; give one or the other");
        }
        if (rule) {
            std::string rp = t.kp("rule");
            Tab r(table_of(*rule->val, rp), rp, {"k_soft", "k_ratio", "m_eff", "zeta"});
            double ks = r.need_num("k_soft", Range::Pos), kr = r.need_num("k_ratio", Range::Pos);
            double me = r.need_num("m_eff", Range::Pos), z = r.num("zeta", 1.0, Range::NonNeg);
            cd_contact_law x = cd_contact_law_from_rule(ks, kr, me, z, l.mu_s);
            if (!(std::isfinite(x.K) && x.K > 0 && std::isfinite(x.D)))
                fail_at(rule->kloc, rp, "the rule gives K = k_soft * k_ratio = " + fmt_num(x.K) + " N/m and D = " + fmt_num(x.D) +
                                           " N s/m; expected finite values (smaller k_soft, k_ratio or m_eff)");
            l.K = x.K;
            l.D = x.D;
        }
        if (K) l.K = num_of(*K->val, t.kp("K"), Range::Pos);
        if (D) l.D = num_of(*D->val, t.kp("D"), Range::NonNeg);
        /* normal damping: the paper's linear D xdot^q, or Hunt-Crossley D x^p xdot^q
         * (docs/contact.md); D's units differ, so a D is never carried across laws */
        Entry *dl = t.get("damping_law");
        if (dl) l.damping = choice_of(*dl->val, t.kp("damping_law"), {"linear", "hunt_crossley"}) == "linear"
                                ? CD_DAMP_LINEAR : CD_DAMP_HUNT_CROSSLEY;
        if (D || rule) s.d_law = l.damping;
        if (rule && l.damping == CD_DAMP_HUNT_CROSSLEY)
            fail_at(rule->kloc, t.kp("rule"), "the 'rule' gives a linear damper D = 2 zeta sqrt(K m); with damping_law = "
                                              "\"hunt_crossley\" give D [N s/m^(p+1)] instead");
        if (s.d_law != l.damping)
            fail_at(dl ? dl->val->loc : t.n->loc, t.kp("D"),
                    std::string("expected D for damping_law = \"") + (l.damping ? "hunt_crossley" : "linear") +
                        "\" here (the D in force was given for the other law, in other units)");
        if (Entry *e = t.get("p")) l.p = num_of(*e->val, t.kp("p"), Range::Ge1);
        if (Entry *e = t.get("q")) l.q = num_of(*e->val, t.kp("q"), Range::Pos);
        if (Entry *e = t.get("p_t")) l.pt = num_of(*e->val, t.kp("p_t"), Range::Ge1);
        if (Entry *e = t.get("q_t")) l.qt = num_of(*e->val, t.kp("q_t"), Range::Pos);
        if (Entry *e = t.get("pull")) l.pull = bool_of(*e->val, t.kp("pull")) ? 1 : 0;
        if (Entry *e = t.get("K_t")) { l.Kt = num_of(*e->val, t.kp("K_t"), Range::Pos); s.kt_set = true; }
        else if (!s.kt_set) l.Kt = l.K;
        if (Entry *e = t.get("D_t")) { l.Dt = num_of(*e->val, t.kp("D_t"), Range::NonNeg); s.dt_set = true; }
        else if (!s.dt_set && l.damping == CD_DAMP_HUNT_CROSSLEY)
            fail_at(t.n->loc, t.kp("D_t"), "expected D_t [N s/m] with damping_law = \"hunt_crossley\" (the tangential "
                                           "damper stays linear, so it cannot default to D)");
        else if (!s.dt_set) l.Dt = l.D;
        Entry *ms = t.get("mu_max"), *mk = t.get("mu");
        if (ms) l.mu_s = num_of(*ms->val, t.kp("mu_max"), Range::NonNeg);
        if (mk) { l.mu_k = num_of(*mk->val, t.kp("mu"), Range::NonNeg); s.mu_set = true; }
        else if (!s.mu_set) l.mu_k = l.mu_s;
        if (l.mu_k > l.mu_s) {
            if (mk) fail_at(mk->val->loc, t.kp("mu"), "expected mu <= mu_max = " + fmt_num(l.mu_s) + ", got " + fmt_num(l.mu_k));
            fail_at(ms ? ms->val->loc : t.n->loc, t.kp("mu_max"),
                    "expected mu_max >= mu = " + fmt_num(l.mu_k) + ", got " + fmt_num(l.mu_s));
        }
        return s;
    }

    void pair(Node &node, const std::string &path, const LawState &def, int &def_law)
    {
        std::vector<std::string> keys = {"name", "checkpoints", "shape"};
        keys.insert(keys.end(), LAW_KEYS.begin(), LAW_KEYS.end());
        Tab t(&node, path, keys);
        if (Entry *e = t.get("name")) {
            /* overrides address a pair by its name (pair.NAME.K): one pair per name */
            std::string nm = name_of_node(*e->val, t.kp("name"));
            if (!pair_names.insert(nm).second)
                fail_at(e->val->loc, t.kp("name"), "expected a pair name used once, got '" + nm + "' twice");
        }
        /* checkpoints = "system" or "system/link" ("system/base" for the base body) */
        const Node &cn = t.need("checkpoints", "\"system\" or \"system/link\"");
        std::string cs = str_of(cn, t.kp("checkpoints"));
        std::string sname = cs.substr(0, cs.find('/'));
        SysInfo *cps = find_sys(sname);
        if (!cps)
            fail_at(cn.loc, t.kp("checkpoints"), "expected \"system\" or \"system/link\", got '" + cs + "': no system '" + sname + "'" +
                    hint(sname, sys_names()));
        int body = -1, ncp = 0;
        if (cs.find('/') != std::string::npos) {
            std::string bn = cs.substr(cs.find('/') + 1);
            auto it = cps->body_at.find(bn);
            if (it == cps->body_at.end())
                fail_at(cn.loc, t.kp("checkpoints"),
                        "expected \"system/link\", got '" + cs + "': system '" + sname + "' has no link '" + bn + "'" +
                            hint(bn, cps->body_names()));
            body = cps->bodies[it->second].id;
            ncp = cps->bodies[it->second].ncp;
            if (ncp == 0)
                fail_at(cn.loc, t.kp("checkpoints"), "expected a body with check points, got '" + cs + "' which has none");
        } else {
            ncp = cps->ncp;
            if (ncp == 0)
                fail_at(cn.loc, t.kp("checkpoints"), "expected a system with check points, got '" + cs + "' which has none");
        }
        /* shape = "system/shape", or "system" when that system has exactly one shape */
        const Node &sn = t.need("shape", "\"system/shape\"");
        std::string ss = str_of(sn, t.kp("shape"));
        std::string shs = ss.substr(0, ss.find('/'));
        SysInfo *shsys = find_sys(shs);
        if (!shsys)
            fail_at(sn.loc, t.kp("shape"), "expected \"system/shape\", got '" + ss + "': no system '" + shs + "'" + hint(shs, sys_names()));
        int shape = -1;
        if (ss.find('/') != std::string::npos) {
            std::string nm = ss.substr(ss.find('/') + 1);
            auto it = shsys->shape_at.find(nm);
            if (it != shsys->shape_at.end()) shape = shsys->shapes[it->second].second;
            if (shape < 0)
                fail_at(sn.loc, t.kp("shape"),
                        "expected \"system/shape\", got '" + ss + "': system '" + shs + "' has no shape '" + nm + "'" +
                            (shsys->shapes.empty() ? std::string(" (it has no shapes)") : hint(nm, shsys->shape_names())));
        } else {
            if (shsys->shapes.size() != 1)
                fail_at(sn.loc, t.kp("shape"),
                        "expected \"system/shape\", got '" + ss + "': system '" + shs + "' has " +
                            std::to_string(shsys->shapes.size()) + " shapes, name one" +
                            (shsys->shapes.empty() ? std::string() : " (" + list(shsys->shape_names()) + ")"));
            shape = shsys->shapes[0].second;
        }
        bool own = false;
        for (auto &k : LAW_KEYS)
            if (t.get(k.c_str())) own = true;
        int lid;
        if (own) {
            LawState ls = law(t, def);
            lid = cd_model_add_law(m.get(), &ls.law, &err);
            if (lid < 0) builder_fail(node.loc, path);
        } else {
            if (def_law < 0) {
                def_law = cd_model_add_law(m.get(), &def.law, &err);
                if (def_law < 0) builder_fail(node.loc, path);
            }
            lid = def_law;
        }
        if (cd_model_add_pair(m.get(), cps->id, body, shape, lid, &err) < 0) builder_fail(node.loc, path);
    }


    /* The work of a run is bounded before it starts: max_rhs_evals and
     * max_wall_time (0 = no limit) are enforced during the run (the CLI's
     * step callback); here the least work the run can take (its steps are at
     * most h_max, or exactly h_fixed, and end at every sample) must fit in
     * max_rhs_evals, so that duration = 1e300 is refused by `check`. */
    void work_budget(const Tab &t, Node &sn, Run &run)
    {
        const cd_options &o = m->opt;
        run.max_wall_time = t.num("max_wall_time", run.max_wall_time, Range::NonNeg);
        run.max_rhs_evals = t.num("max_rhs_evals", run.max_rhs_evals, Range::NonNeg);
        if (Entry *e = t.get("max_rhs_evals")) int_of(*e->val, t.kp("max_rhs_evals"), 0);
        /* right-hand-side evaluations per step, at least: the stages of the
         * explicit steppers that are not reused; one for the implicit ones */
        double per_step = 1;
        const char *hname = "h_max";
        double h = o.h_max;
        switch (o.stepper) {
        case CD_STEP_RKF45: case CD_STEP_RKCK: per_step = 5; break;
        case CD_STEP_RK8PD: per_step = 12; break;
        case CD_STEP_ROS34PW2: per_step = 4; break;
        case CD_STEP_AUTO: per_step = 2; break; /* at least the stiff stepper's: msbdf, a Newton iteration and f(t1) */
        case CD_STEP_RODAS4: per_step = 6; break;
        case CD_STEP_RK4_FIXED: per_step = 4; hname = "h_fixed"; h = o.h_fixed; break;
        default: break;
        }
        double samples = run.interpolate ? 1.0 : std::ceil(run.duration / run.output_dt - 1e-9);
        double steps = h > 0 ? std::max(samples, std::ceil(run.duration / h - 1e-9)) : samples;
        run.min_steps = steps;
        run.min_rhs_evals = steps * per_step;
        if (run.max_rhs_evals > 0 && run.min_rhs_evals > run.max_rhs_evals) {
            Entry *e = t.get("duration");
            fail_at(e ? e->val->loc : sn.loc, t.kp("duration"),
                    "expected a run within max_rhs_evals = " + fmt_num(run.max_rhs_evals) +
                        " right-hand-side evaluations, got one needing at least " + fmt_num(run.min_rhs_evals) + " (" +
                        fmt_num(steps) + " steps of at most " + hname + " = " + fmt_num(h) + " s, " + fmt_num(per_step) +
                        " evaluations each, for duration = " + fmt_num(run.duration) +
                        " s); shorten the duration or raise simulation.max_rhs_evals");
        }
    }

    /* [simulation]: the run's options, duration and sampling, its work budget */
    void simulation(const Tab &top, Run &run)
    {
        Node &sn = *table_of(top.need("simulation", "a [simulation] table with at least duration"), "simulation");
        Tab t(&sn, "simulation",
              {"duration", "gravity", "integrator", "rtol", "atol", "h_init", "h_max", "h_min", "h_fixed", "max_steps",
               "event_tol", "dwell", "v_reg", "fd_eps", "jacobian", "output_dt", "flush_every", "event_capacity",
               "equilibrium_start", "max_wall_time", "max_rhs_evals", "sampling", "compress"});
        cd_options &o = m->opt;
        run.duration = t.need_num("duration", Range::Pos);
        t.vec("gravity", 3, m->gravity);
        if (Entry *e = t.get("integrator")) {
            std::vector<std::string> names;
            for (int i = 0; i < CD_STEP_NTYPES; i++) names.push_back(cd_stepper_name((cd_stepper)i));
            o.stepper = (cd_stepper)cd_stepper_from_name(choice_of(*e->val, t.kp("integrator"), names).c_str());
        }
        o.rtol = t.num("rtol", o.rtol, Range::NonNeg);
        if (o.rtol > 0 && o.rtol < CD_RTOL_MIN)
            fail_at(t.get("rtol") ? t.get("rtol")->val->loc : sn.loc, t.kp("rtol"),
                    "expected 0 or a value in [" + fmt_num(CD_RTOL_MIN) +
                        ", inf) (a tighter relative tolerance cannot be met in double precision), got " + fmt_num(o.rtol));
        o.atol = t.num("atol", o.atol, Range::NonNeg);
        if (!(o.rtol + o.atol > 0))
            fail_at(t.get("atol") ? t.get("atol")->val->loc : sn.loc, t.kp("atol"), "expected rtol + atol > 0, got both 0");
        o.h_init = t.num("h_init", o.h_init, Range::Pos);
        o.h_max = t.num("h_max", o.h_max, Range::NonNeg);
        o.h_min = t.num("h_min", o.h_min, Range::NonNeg);
        if (o.h_max > 0 && o.h_min > o.h_max)
            fail_at(t.get("h_min") ? t.get("h_min")->val->loc : sn.loc, t.kp("h_min"),
                    "expected h_min <= h_max = " + fmt_num(o.h_max) + ", got " + fmt_num(o.h_min));
        o.h_fixed = t.num("h_fixed", o.h_fixed, Range::Pos);
        if (Entry *e = t.get("max_steps")) o.max_steps = (long)int_of(*e->val, t.kp("max_steps"), 1);
        o.event_tol = t.num("event_tol", o.event_tol, Range::Pos);
        o.dwell = t.num("dwell", o.dwell, Range::NonNeg);
        o.v_reg = t.num("v_reg", o.v_reg, Range::Pos);
        o.fd_eps = t.num("fd_eps", o.fd_eps, Range::Pos);
        if (Entry *e = t.get("jacobian"))
            o.jacobian = choice_of(*e->val, t.kp("jacobian"), {"model", "fd"}) == "fd" ? CD_JAC_FD : CD_JAC_MODEL;
        if (Entry *e = t.get("equilibrium_start")) o.equilibrium_start = bool_of(*e->val, t.kp("equilibrium_start")) ? 1 : 0;
        run.output_dt = t.num("output_dt", run.duration / 1000.0, Range::Pos);
        /* the sample count must be a sane integer (the CLI converts it) */
        if (!(run.duration / run.output_dt <= CD_SCENARIO_MAX_SAMPLES)) {
            Entry *e = t.get("output_dt");
            if (!e) e = t.get("duration");
            fail_at(e ? e->val->loc : sn.loc, t.kp("output_dt"),
                    "expected a value in [duration / 1e9, inf) = [" + fmt_num(run.duration / CD_SCENARIO_MAX_SAMPLES) +
                        ", inf) s (at most 1e9 samples for duration = " + fmt_num(run.duration) + " s), got " +
                        fmt_num(run.output_dt));
        }
        run.flush_every = t.num("flush_every", 1.0, Range::Pos);
        /* samples: "stop" (the integrator ends a step at each) or
         * "interpolate" (dense output); the stiff stepper interpolates by default */
        run.interpolate = o.stepper == CD_STEP_ROS34PW2 || o.stepper == CD_STEP_AUTO || o.stepper == CD_STEP_RODAS4;
        if (Entry *e = t.get("sampling")) run.interpolate = choice_of(*e->val, t.kp("sampling"), {"stop", "interpolate"}) == "interpolate";
        if (run.interpolate && o.stepper == CD_STEP_RK4_FIXED) {
            Entry *e = t.get("sampling");
            fail_at(e ? e->val->loc : sn.loc, t.kp("sampling"), "expected \"stop\" with integrator = \"rk4\" (fixed steps land on the samples), got \"interpolate\"");
        }
        if (Entry *e = t.get("compress")) run.no_compress = !bool_of(*e->val, t.kp("compress"));
        work_budget(t, sn, run);
        if (Entry *e = t.get("event_capacity")) {
            long long v = int_of(*e->val, t.kp("event_capacity"), 1);
            if (v > 100000000LL) fail_at(e->val->loc, t.kp("event_capacity"), "expected an integer in [1, 1e8], got " + render(*e->val));
            run.event_capacity = (int)v;
        }
    }

    /* [capture]: the verdict's object and thresholds (verdict.h) */
    void capture(const Tab &top, Run &run)
    {
    for (auto &s2 : sys)
        if (s2.is_target && run.object < 0 && m->sys_base_type[s2.id] == CD_BASE_FREE) run.object = s2.id;
    if (Entry *e = top.get("capture")) {
        Tab t(table_of(*e->val, "capture"), "capture", {"object", "feature", "v_max", "w_max", "dwell", "workspace"});
        if (Entry *o = t.get("object")) {
            std::string on = str_of(*o->val, t.kp("object"));
            SysInfo *os = find_sys(on);
            if (!os) fail_at(o->val->loc, t.kp("object"), "expected the name of a system, got '" + on + "'" + hint(on, sys_names()));
            if (m->sys_base_type[os->id] != CD_BASE_FREE)
                fail_at(o->val->loc, t.kp("object"), "expected a free-floating system, got '" + on + "' (fixed base)");
            run.object = os->id;
        }
        if (Entry *f = t.get("feature")) {
            std::string fn = str_of(*f->val, t.kp("feature"));
            SysInfo *os = run.object >= 0 ? &sys[0] : nullptr;
            for (auto &s2 : sys)
                if (s2.id == run.object) os = &s2;
            if (!os || !os->shape_at.count(fn))
                fail_at(f->val->loc, t.kp("feature"), "expected the name of a shape of the object" +
                                                         (os ? " '" + os->name + "'" + hint(fn, os->shape_names()) : std::string()) +
                                                         ", got '" + fn + "'");
            run.feature = os->shapes[os->shape_at[fn]].second;
        }
        run.v_max = t.num("v_max", run.v_max, Range::Pos);
        run.w_max = t.num("w_max", run.w_max, Range::Pos);
        run.dwell = t.num("dwell", run.dwell, Range::NonNeg);
        run.workspace = t.num("workspace", run.workspace, Range::Pos);
    }
    }

    /* [gripper] of type 'torque' (the hand is a [[system]]) or the rest of a
     * generated hand (stage 1 was built after its host system, if mounted) */
    void gripper(const Tab &t, const std::string &ty, const std::string &gsys, bool mounted, const LawState &def, Run &run)
    {
        if (ty == "torque") {
            for (auto &k : t.n->tab)
                if (k.key != "type" && k.key != "system")
                    fail_at(k.kloc, t.kp(k.key.c_str()), "does not apply to a 'torque' gripper (its hand is a [[system]] with link actuators)");
            if (Entry *g = t.get("system")) {
                std::string gs = str_of(*g->val, t.kp("system"));
                if (!find_sys(gs))
                    fail_at(g->val->loc, t.kp("system"), "expected the name of a system, got '" + gs + "'" + hint(gs, sys_names()));
                run.hand = find_sys(gs)->id;
            }
            /* type "torque": the joints are driven by their own `actuator` tables */
        } else {
            if (!gsys.empty() && !mounted) {
                /* not a [[system]] (a target, or no such name): stage 1 says why */
                gripper_hand(t, ty, def, run, 1);
                fail_at(t.get("system")->val->loc, t.kp("system"), "expected a [[system]] name, got '" + gsys + "'");
            }
            gripper_hand(t, ty, def, run, mounted ? 2 : 0);
        }
    }

    void build(Node &root, Run &run, const std::string &path)
    {
        m.reset(cd_model_create());
        if (!m) throw std::bad_alloc();
        Tab top(&root, "", {"title", "include", "simulation", "contact", "system", "target", "pair", "gripper", "actuator",
                            "capture", "control"});
        if (Entry *e = top.get("include"))
            fail_at(e->kloc, "include", "expected 'include' only at the top of a file, got it from an override");

        /* title (default: the file name without directory and extension) */
        if (Entry *e = top.get("title")) {
            run.title = str_of(*e->val, "title");
            if (run.title.size() > CD_TITLE_MAX)
                fail_at(e->val->loc, "title", "expected a title of at most " + std::to_string(CD_TITLE_MAX) + " bytes, got " +
                                                   std::to_string(run.title.size()));
        } else {
            run.title = std::filesystem::path(path).stem().string();
        }

        simulation(top, run);

        /* [contact] defaults */
        LawState def;
        def.law = cd_contact_law_default();
        if (Entry *e = top.get("contact")) {
            Tab t(table_of(*e->val, "contact"), "contact", LAW_KEYS);
            def = law(t, def);
        }

        /* systems, then targets (their ids follow this order) */
        Entry *se = top.get("system"), *te = top.get("target");
        if (!se && !te)
            fail_at(root.loc, "system", "missing required key (expected at least one [[system]] or [[target]])");
        /* a mechanism gripper mounted on a system's link: its fingers are
         * built right after that system's links (bodies of a system are
         * contiguous) */
        std::unique_ptr<Tab> gt;
        std::string gty, gsys;
        if (Entry *e = top.get("gripper")) {
            gt.reset(new Tab(table_of(*e->val, "gripper"), "gripper",
                             {"type", "system", "attach", "name", "hand", "palm", "links", "masses", "radius", "spacing",
                              "checkpoint_spacing", "close", "torque", "open_at", "ratios", "motor", "clutch", "finger_joint", "pair_offset",
                              "finger_contact"}));
            const Node &tn = gt->need("type", "one of 'torque', 'soft', 'tako', 'space', 'torque_switch'");
            gty = choice_of(tn, gt->kp("type"), {"torque", "soft", "tako", "space", "torque_switch"});
            if (gty != "torque")
                if (Entry *g = gt->get("system")) gsys = str_of(*g->val, gt->kp("system"));
        }
        bool mounted = false;
        if (se) {
            auto v = tables_of(*se->val, "system", "[[system]]");
            for (size_t i = 0; i < v.size(); i++) {
                system(*v[i], se->val->kind == NK::Array ? idx("system", i) : "system", false);
                if (!gsys.empty() && sys.back().name == gsys) {
                    gripper_hand(*gt, gty, def, run, 1);
                    mounted = true;
                }
            }
        }
        if (te) {
            auto v = tables_of(*te->val, "target", "[[target]]");
            for (size_t i = 0; i < v.size(); i++) system(*v[i], te->val->kind == NK::Array ? idx("target", i) : "target", true);
        }

        /* [[actuator]]: transmissions (after every system: they name joints) */
        if (Entry *e = top.get("actuator")) {
            auto v = tables_of(*e->val, "actuator", "[[actuator]]");
            for (size_t i = 0; i < v.size(); i++) transmission_actuator(*v[i], e->val->kind == NK::Array ? idx("actuator", i) : "actuator");
        }

        /* [gripper] */
        if (gt) gripper(*gt, gty, gsys, mounted, def, run);

        capture(top, run);
        if (run.hand == run.object) run.object = -1;

        /* [control] (after the gripper: it closes the gripper's motors) */
        if (Entry *e = top.get("control")) control(*e, run);
        else if (run.close_trigger)
            fail_at(top.get("gripper")->val->loc, "gripper.close.on", "expected 'time' without a [control] table (it has the grasp trigger)");

        /* [[pair]] */
        if (Entry *e = top.get("pair")) {
            int def_law = -1;
            auto v = tables_of(*e->val, "pair", "[[pair]]");
            for (size_t i = 0; i < v.size(); i++) pair(*v[i], e->val->kind == NK::Array ? idx("pair", i) : "pair", def, def_law);
        }

        if (cd_model_finalize(m.get(), &err) != CD_OK) builder_fail(root.loc, "");
        place_in_palm(run);
    }

    /* Targets given with frame = "palm": their position, orientation,
     * velocity and angular velocity were read relative to the palm (the
     * hand's palm body at the initial state, a moving frame if the hand
     * moves: velocities are relative to it, in its axes); here they become
     * world values. Done on the finalized model, whose initial kinematics
     * place the palm (a hand on an arm is posed by the arm's q0). */
    void place_in_palm(const Run &run)
    {
        const SysInfo *first = nullptr;
        for (auto &s2 : sys)
            if (s2.in_palm && !first) first = &s2;
        if (!first) return;
        for (auto &s2 : sys)
            if (s2.in_palm && run.hand < 0)
                fail_at(s2.frame_loc, s2.path + ".frame", "expected \"world\": frame = \"palm\" needs a hand (a [gripper] table)");
        /* the pose given by q0 (not a settled one: the settle, if asked
         * for, runs at the start of the run with the targets in place) */
        int eq = m->opt.equilibrium_start;
        m->opt.equilibrium_start = 0;
        std::unique_ptr<cd_data, void (*)(cd_data *)> d(cd_data_create(m.get(), 16, &err), cd_data_free);
        m->opt.equilibrium_start = eq;
        if (!d) builder_fail(first->frame_loc, first->path + ".frame");
        cd_kinematics(m.get(), d.get());
        /* the palm frame: run.palm_pos / palm_rot on the palm body */
        int pb = run.palm >= 0 ? run.palm : m->sys_body_adr[run.hand];
        const double *Rb = d->body_R + 9 * pb, *xb = d->body_x + 3 * pb, *w = d->body_w + 3 * pb;
        double R[9], x[3], vp[3];
        {
            double c[3], r[3], wr[3];
            cd_m3_mul(R, Rb, run.palm_rot.data());
            cd_m3_mulv(r, Rb, run.palm_pos.data());
            for (int k = 0; k < 3; k++) x[k] = xb[k] + r[k];
            /* the palm frame origin's velocity: v_com + w x (origin - com) */
            cd_m3_mulv(c, Rb, m->body_com + 3 * pb);
            for (int k = 0; k < 3; k++) r[k] -= c[k];
            cd_v3_cross(wr, w, r);
            for (int k = 0; k < 3; k++) vp[k] = d->body_v[3 * pb + k] + wr[k];
        }
        for (auto &s2 : sys) {
            if (!s2.in_palm) continue;
            int id = s2.id;
            double *p = m->sys_pos0 + 3 * id, *q = m->sys_quat0 + 4 * id, *v = m->sys_vel0 + 3 * id, *om = m->sys_angvel0 + 3 * id;
            double Rt[9], Rw[9], rw[3], vw[3], ow[3], wxr[3];
            cd_m3_mulv(rw, R, p);
            cd_quat_to_m3(Rt, q);
            cd_m3_mul(Rw, R, Rt);
            cd_m3_mulv(vw, R, v);
            cd_m3_mulv(ow, R, om);
            cd_v3_cross(wxr, w, rw);
            for (int k = 0; k < 3; k++) {
                p[k] = x[k] + rw[k];
                v[k] = vp[k] + wxr[k] + vw[k];
                om[k] = w[k] + ow[k];
            }
            cd_m3_to_quat(q, Rw);
            int b0 = m->sys_body_adr[id];
            if (m->body_presc[b0] != CD_PRESCRIBE_NONE) { /* a prescribed base moves at the world values */
                cd_v3_copy(m->body_presc_prm + 6 * b0, v);
                cd_v3_copy(m->body_presc_prm + 6 * b0 + 3, om);
            }
        }
    }
};

char *cdup(const std::string &s)
{
    char *r = (char *)std::malloc(s.size() + 1);
    if (!r) throw std::bad_alloc();
    std::memcpy(r, s.c_str(), s.size() + 1);
    return r;
}

/* The message on one line with no terminal control: control characters
 * (C0, DEL and C1 in UTF-8) that came from the input (keys, strings, file
 * names) are written as \n, \t, \r, \\xNN or \\u00NN; other UTF-8 is kept. */
std::string escape_controls(const std::string &m)
{
    std::string o;
    o.reserve(m.size());
    for (size_t i = 0; i < m.size(); i++) {
        unsigned char c = (unsigned char)m[i];
        char b[8];
        if (c == '\n') o += "\\n";
        else if (c == '\t') o += "\\t";
        else if (c == '\r') o += "\\r";
        else if (c < 0x20 || c == 0x7f) {
            std::snprintf(b, sizeof b, "\\x%02x", c);
            o += b;
        } else if (c == 0xc2 && i + 1 < m.size() && (unsigned char)m[i + 1] >= 0x80 && (unsigned char)m[i + 1] <= 0x9f) {
            std::snprintf(b, sizeof b, "\\u%04x", (unsigned char)m[i + 1]);
            o += b;
            i++;
        } else {
            o += (char)c;
        }
    }
    return o;
}

void set_err(cd_error *err, cd_status st, const std::string &msg)
{
    if (!err) return;
    err->status = st;
    std::string m = escape_controls(msg);
    /* cut at a character boundary, never inside an escape or a UTF-8 sequence */
    size_t cap = sizeof err->msg - 1;
    if (m.size() > cap) {
        size_t cut = cap - 3;
        while (cut > 0 && ((unsigned char)m[cut] & 0xc0) == 0x80) cut--;
        size_t bs = m.rfind('\\', cut);
        if (bs != std::string::npos && cut - bs < 6) cut = bs;
        m = m.substr(0, cut) + "...";
    }
    std::snprintf(err->msg, sizeof err->msg, "%s", m.c_str());
}

void free_scenario(cd_scenario *sc)
{
    if (!sc) return;
    cd_model_free(sc->model);
    std::free(sc->path);
    std::free(sc->title);
    std::free(sc->text);
    std::free(sc->overrides);
    std::free(sc->control);
    std::free(sc->imported);
    std::free(sc->warnings);
    std::free(sc);
}

cd_scenario *load(const char *path, const char *const *overrides, int noverrides)
{
    if (!path) throw LoadError{CD_EINVAL, "scenario path is NULL"};
    if (noverrides < 0 || (noverrides > 0 && !overrides)) throw LoadError{CD_EINVAL, "overrides: bad array"};
    FileLoader fl;
    NodeP root = fl.load(path, nullptr, "");
    std::string ovtext;
    for (int i = 0; i < noverrides; i++) {
        if (!overrides[i]) throw LoadError{CD_EINVAL, "override " + std::to_string(i) + " is NULL"};
        apply_override(root, overrides[i]);
        ovtext += overrides[i];
        ovtext += "\n";
    }
    Builder b;
    Builder::Run run;
    b.build(*root, run, path);

    cd_scenario *sc = (cd_scenario *)std::calloc(1, sizeof *sc);
    if (!sc) throw std::bad_alloc();
    try {
        sc->path = cdup(path);
        sc->title = cdup(run.title);
        sc->text = cdup(fl.text);
        sc->overrides = cdup(ovtext);
    } catch (...) {
        free_scenario(sc);
        throw;
    }
    sc->model = b.m.release();
    sc->duration = run.duration;
    sc->output_dt = run.output_dt;
    sc->flush_every = run.flush_every;
    sc->event_capacity = run.event_capacity;
    sc->interpolate = run.interpolate ? 1 : 0;
    sc->no_compress = run.no_compress ? 1 : 0;
    sc->capture_hand = run.hand;
    sc->capture_object = run.object;
    sc->capture_v_max = run.v_max;
    sc->capture_w_max = run.w_max;
    sc->capture_dwell = run.dwell;
    sc->capture_workspace = run.workspace;
    sc->capture_feature = run.feature;
    if (run.control) {
        sc->control = (cd_ctrl_config *)std::malloc(sizeof *sc->control);
        if (!sc->control) {
            free_scenario(sc);
            throw std::bad_alloc();
        }
        *sc->control = *run.control;
    }
    sc->capture_palm = run.palm;
    for (int k = 0; k < 3; k++) sc->capture_palm_pos[k] = run.palm_pos[k];
    for (int k = 0; k < 9; k++) sc->capture_palm_rot[k] = run.palm_rot[k];
    sc->max_wall_time = run.max_wall_time;
    sc->max_rhs_evals = run.max_rhs_evals;
    sc->min_steps = run.min_steps;
    sc->min_rhs_evals = run.min_rhs_evals;
    try { /* URDF imports: the trees `capdyn check` prints, and the warnings */
        std::string tree;
        for (auto &x : b.urdfs) {
            char *d = cd_urdf_describe(x.first.get(), sc->model, x.second);
            if (d) {
                try {
                    tree += d;
                } catch (...) {
                    std::free(d);
                    throw;
                }
            }
            std::free(d);
        }
        sc->imported = cdup(tree);
        sc->warnings = cdup(b.warnings);
        if (!sc->imported || !sc->warnings) throw std::bad_alloc();
    } catch (...) {
        /* the scenario owns the model by now: out of memory here frees both */
        free_scenario(sc);
        throw;
    }
    return sc;
}

}  // namespace

extern "C" cd_scenario *cd_scenario_load(const char *path, const char *const *overrides, int noverrides,
                                         cd_error *err)
{
    try {
        cd_scenario *sc = load(path, overrides, noverrides);
        if (err) {
            err->status = CD_OK;
            err->msg[0] = 0;
        }
        return sc;
    } catch (const LoadError &e) {
        set_err(err, e.st, e.msg);
    } catch (const std::bad_alloc &) {
        set_err(err, CD_ENOMEM, "out of memory while loading the scenario");
    } catch (const std::exception &e) {
        set_err(err, CD_EINVAL, std::string("internal error while loading the scenario: ") + e.what());
    } catch (...) {
        set_err(err, CD_EINVAL, "internal error while loading the scenario");
    }
    return nullptr;
}

extern "C" void cd_scenario_free(cd_scenario *sc) { free_scenario(sc); }
