// Hand-built parameter lists with known locations ("test.pbrt:line:col").
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "parser/scene_desc.h"

namespace gradus::params_test {

inline FileLoc Loc(int line, int column) {
    static const auto file = std::make_shared<const std::string>("test.pbrt");
    FileLoc l;
    l.file = file;
    l.line = line;
    l.column = column;
    return l;
}

// A directive at test.pbrt:1:1; parameters are added with their own locations.
struct Desc {
    EntityDesc desc;
    explicit Desc(const std::string &type = "") {
        desc.type = type;
        desc.loc = Loc(1, 1);
        desc.present = true;
    }
    Desc &add(const std::string &type, const std::string &name, FileLoc loc, std::vector<double> numbers = {},
              std::vector<std::string> strings = {}, std::vector<bool> bools = {}) {
        Param p;
        p.type = type;
        p.name = name;
        p.loc = loc;
        p.numbers = std::move(numbers);
        p.strings = std::move(strings);
        p.bools = std::move(bools);
        desc.params.add(std::move(p));
        return *this;
    }
    Desc &integer(const std::string &name, std::vector<double> v, FileLoc loc = Loc(2, 1)) {
        return add("integer", name, loc, std::move(v));
    }
    Desc &real(const std::string &name, double v, FileLoc loc = Loc(2, 1)) { return add("float", name, loc, {v}); }
    Desc &string(const std::string &name, const std::string &v, FileLoc loc = Loc(2, 1)) {
        return add("string", name, loc, {}, {v});
    }
    Desc &boolean(const std::string &name, bool v, FileLoc loc = Loc(2, 1)) {
        return add("bool", name, loc, {}, {}, {v});
    }
};

}  // namespace gradus::params_test
