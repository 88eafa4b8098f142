// Typed parameter tables of the integrators. A table lists every parameter an
// integrator reads (name, type, default, help, accepted values) and
//   (a) parses an EntityDesc's ParamSet into a settings struct: every entry is
//       looked up (so the scene builder's checkUnused still catches misspelt
//       names), out-of-range numbers and unknown or unsupported enumeration
//       values throw an Error at the parameter's file:line:col;
//   (b) describes itself (`gradus --describe NAME`, the header doc test).
// Family parts (path tracing, bidirectional, gradient) are tables of a base
// settings struct, appended to the table of an integrator whose settings
// derive from it.
#pragma once
#include <functional>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/error.h"
#include "parser/scene_desc.h"

namespace gradus {

enum class ParamKind { Bool, Int, Float, String, Enum, IntList };

// Self-description of one entry.
struct ParamInfo {
    std::string name;
    ParamKind kind = ParamKind::String;
    std::string defaultText;  // as written in a scene file: 5, 0.001, "power", false, []
    std::string help;
    std::string values;       // accepted values when restricted: "balance | power", ">= 0"; else ""
    std::string group;        // heading: the family or integrator the entry comes from
    // pbrt-v3 type name in scene files: bool, integer, float or string.
    const char *typeName() const;
};

// --describe text: entries under their group headings, one line each
// (name, type, default, help), restricted values on the next line.
std::string FormatParams(const std::vector<ParamInfo> &params);

// Inclusive bounds of a number; `why` explains the restriction in the error.
struct Range {
    Range(double lo = -std::numeric_limits<double>::infinity(), double hi = std::numeric_limits<double>::infinity(),
          std::string why = "")
        : lo(lo), hi(hi), why(std::move(why)) {}
    double lo, hi;
    std::string why;
    bool contains(double v) const { return v >= lo && v <= hi; }  // false for NaN
    std::string text() const;  // ">= 0", "in [1, 1024]", "-1"; "" when unbounded
    std::string describe() const { return why.empty() ? text() : text() + ": " + why; }
};
inline Range AtLeast(double lo) { return Range(lo); }

// One value of an enumeration.
template <class T>
struct Choice {
    Choice(std::string name, T value, std::string unsupported = "", bool alias = false)
        : name(std::move(name)), value(value), unsupported(std::move(unsupported)), alias(alias) {}
    std::string name;
    T value;
    std::string unsupported;  // non-empty: rejected with this reason ("is not supported by gbdpt yet")
    bool alias = false;       // accepted but not listed (e.g. "L1" for "l1")
};

namespace params_detail {
std::string Number(double v);  // %g
std::string Quote(const std::string &s);
[[noreturn]] void RangeError(const FileLoc &loc, const std::string &name, const Range &r);
[[noreturn]] void ChoiceError(const FileLoc &loc, const std::string &name, const std::string &value,
                              const std::string &reason, const std::vector<std::string> &valid);
}  // namespace params_detail

// pbrt-v3's default path depth, shared by every integrator family.
constexpr int kDefaultMaxDepth = 5;

template <class S>
class ParamTable {
  public:
    // `group`: heading of the entries added to this table.
    explicit ParamTable(std::string group) : group_(std::move(group)) {}

    ParamTable &boolean(const std::string &name, bool S::*field, bool def, const std::string &help) {
        return add(ParamInfo{name, ParamKind::Bool, def ? "true" : "false", help, "", group_},
                   [=](const ParamSet &ps, const FileLoc &, S &s) { s.*field = ps.getBool(name, def); });
    }
    ParamTable &integer(const std::string &name, int S::*field, int def, const std::string &help,
                        const Range &range = {}) {
        return number(ParamKind::Int, name, field, def, help, range);
    }
    ParamTable &real(const std::string &name, Float S::*field, Float def, const std::string &help,
                     const Range &range = {}) {
        return number(ParamKind::Float, name, field, def, help, range);
    }
    ParamTable &string(const std::string &name, std::string S::*field, const std::string &def,
                       const std::string &help) {
        return add(ParamInfo{name, ParamKind::String, params_detail::Quote(def), help, "", group_},
                   [=](const ParamSet &ps, const FileLoc &, S &s) { s.*field = ps.getString(name, def); });
    }
    // A string naming one of `choices`; `def` is the name of the default.
    template <class T>
    ParamTable &enumeration(const std::string &name, T S::*field, const std::string &def,
                            std::vector<Choice<T>> choices, const std::string &help);
    // Values that are their own names (string fields).
    ParamTable &enumeration(const std::string &name, std::string S::*field, const std::string &def,
                            const std::vector<std::string> &names, const std::string &help) {
        std::vector<Choice<std::string>> c;
        for (const auto &n : names) c.push_back({n, n});
        return enumeration(name, field, def, std::move(c), help);
    }
    // The parameters every family shares, written once: pbrt-v3's "maxdepth"
    // (default 5) and "pixelbounds" (accepted; the job checks it covers the film).
    ParamTable &maxDepth(int S::*field) {
        return integer("maxdepth", field, kDefaultMaxDepth, "maximum path depth (bounces; edges - 1)", AtLeast(0));
    }
    ParamTable &pixelBounds(std::vector<int> S::*field) {
        return integers("pixelbounds", field, "accepted (use --cropwindow instead)");
    }
    // An integer list (default empty).
    ParamTable &integers(const std::string &name, std::vector<int> S::*field, const std::string &help) {
        return add(ParamInfo{name, ParamKind::IntList, "[]", help, "", group_},
                   [=](const ParamSet &ps, const FileLoc &, S &s) { s.*field = ps.getInts(name); });
    }
    // Runs after the last added entry is read, with that parameter's location
    // (the directive's if absent): derived fields, checks against earlier entries.
    ParamTable &then(std::function<void(S &, const FileLoc &)> fn) {
        return thenWithParams([fn = std::move(fn)](S &s, const ParamSet &, const FileLoc &loc) { fn(s, loc); });
    }
    // As then(), with the parameter set (to tell given parameters from defaults).
    ParamTable &thenWithParams(std::function<void(S &, const ParamSet &, const FileLoc &)> fn) {
        GRADUS_CHECK(!entries_.empty());
        Entry &e = entries_.back();
        e.read = [prev = e.read, fn = std::move(fn), name = e.info.name](const ParamSet &ps, const FileLoc &loc,
                                                                         S &s) {
            prev(ps, loc, s);
            fn(s, ps, ps.locOf(name, loc));
        };
        return *this;
    }
    // Appends a family part (S derives from Base); its entries keep their group.
    template <class Base>
    ParamTable &append(const ParamTable<Base> &part) {
        static_assert(std::is_base_of_v<Base, S>, "settings must derive from the part's settings");
        for (const auto &e : part.entries_) {
            checkNew(e.info.name);
            entries_.push_back({e.info, [read = e.read](const ParamSet &ps, const FileLoc &loc, S &s) {
                                    read(ps, loc, static_cast<Base &>(s));
                                }});
        }
        return *this;
    }

    // Reads every entry from desc.params (marking each used), in table order.
    S parse(const EntityDesc &desc) const {
        S s{};
        for (const Entry &e : entries_) e.read(desc.params, desc.loc, s);
        return s;
    }
    std::vector<ParamInfo> describe() const {
        std::vector<ParamInfo> r;
        for (const Entry &e : entries_) r.push_back(e.info);
        return r;
    }

  private:
    template <class>
    friend class ParamTable;
    using Reader = std::function<void(const ParamSet &, const FileLoc &, S &)>;
    struct Entry {
        ParamInfo info;
        Reader read;
    };
    void checkNew(const std::string &name) const {
        for (const Entry &e : entries_) GRADUS_CHECK(e.info.name != name);
    }
    template <class T>
    ParamTable &number(ParamKind kind, const std::string &name, T S::*field, T def, const std::string &help,
                       const Range &range) {
        std::string defText;
        if constexpr (std::is_same_v<T, int>)
            defText = std::to_string(def);
        else
            defText = params_detail::Number(def);
        return add(ParamInfo{name, kind, defText, help, range.describe(), group_},
                   [=](const ParamSet &ps, const FileLoc &loc, S &s) {
                       T v;
                       if constexpr (std::is_same_v<T, int>)
                           v = ps.getInt(name, def);
                       else
                           v = ps.getFloat(name, def);
                       if (!range.contains(v)) params_detail::RangeError(ps.locOf(name, loc), name, range);
                       s.*field = v;
                   });
    }
    ParamTable &add(ParamInfo info, Reader read) {
        checkNew(info.name);
        entries_.push_back({std::move(info), std::move(read)});
        return *this;
    }
    std::string group_;
    std::vector<Entry> entries_;
};

template <class S>
template <class T>
ParamTable<S> &ParamTable<S>::enumeration(const std::string &name, T S::*field, const std::string &def,
                                          std::vector<Choice<T>> choices, const std::string &help) {
    std::vector<std::string> valid;
    std::string values, rejected;
    bool defaultOk = false;
    for (const auto &c : choices) {
        defaultOk |= c.name == def && c.unsupported.empty();
        if (c.alias) continue;
        if (!c.unsupported.empty()) {
            rejected += "; " + params_detail::Quote(c.name) + " " + c.unsupported;
            continue;
        }
        valid.push_back(c.name);
        values += (values.empty() ? "" : " | ") + c.name;
    }
    GRADUS_CHECK(defaultOk);
    return add(ParamInfo{name, ParamKind::Enum, params_detail::Quote(def), help, values + rejected, group_},
               [=](const ParamSet &ps, const FileLoc &loc, S &s) {
                   std::string v = ps.getString(name, def);
                   for (const auto &c : choices)
                       if (c.name == v) {
                           if (!c.unsupported.empty())
                               params_detail::ChoiceError(ps.locOf(name, loc), name, v, c.unsupported, valid);
                           s.*field = c.value;
                           return;
                       }
                   params_detail::ChoiceError(ps.locOf(name, loc), name, v, "", valid);
               });
}

}  // namespace gradus
