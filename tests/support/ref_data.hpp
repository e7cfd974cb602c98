// Reference data written at test time by the python scripts in tests/ref (tests/ref/refio.py).
// Plain text so that the reference path depends on none of the library's own parsers:
//   <name> <ndim> <d0> ... <dn-1>\n<values, whitespace separated, %.17g>\n   (repeated)
#pragma once

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace hawor_test {

struct RefArray {
  std::vector<long> shape;
  std::vector<double> data;  // row-major (C order)
  long size() const { return static_cast<long>(data.size()); }
  double operator[](long i) const { return data.at(static_cast<size_t>(i)); }
};

class RefData {
 public:
  static RefData load(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("reference file missing: " + path);
    RefData r;
    std::string name;
    while (in >> name) {
      int ndim = 0;
      in >> ndim;
      RefArray a;
      long n = 1;
      for (int i = 0; i < ndim; ++i) {
        long d = 0;
        in >> d;
        a.shape.push_back(d);
        n *= d;
      }
      a.data.resize(static_cast<size_t>(n));
      for (long i = 0; i < n; ++i) {
        std::string tok;
        in >> tok;
        a.data[static_cast<size_t>(i)] = std::strtod(tok.c_str(), nullptr);  // handles nan/inf
      }
      if (!in) throw std::runtime_error("truncated reference file: " + path);
      r.arrays_[name] = std::move(a);
    }
    return r;
  }
  const RefArray& operator[](const std::string& name) const {
    auto it = arrays_.find(name);
    if (it == arrays_.end()) throw std::runtime_error("reference array missing: " + name);
    return it->second;
  }
  bool has(const std::string& name) const { return arrays_.count(name) != 0; }

 private:
  std::map<std::string, RefArray> arrays_;
};

/// Runs `/usr/bin/python3 tests/ref/<script> <out> [args]` and loads what it wrote.
/// Native only: the WASM build has no processes.
inline RefData runReference(const std::string& script, const std::string& outName,
                            const std::string& args = "") {
  const std::string out = std::string(HAWOR_REF_DIR) + "/" + outName;
  const std::string cmd = std::string(HAWOR_PYTHON) + " " + HAWOR_SOURCE_DIR + "/tests/ref/" +
                          script + " " + out + " " + args;
  const int rc = std::system(cmd.c_str());
  if (rc != 0) throw std::runtime_error("reference script failed: " + cmd);
  return RefData::load(out);
}

}  // namespace hawor_test
