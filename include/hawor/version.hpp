// hawor/version.hpp — the library's version (semantic versioning: while the major version is 0,
// a new minor version may change the API). CMake's project(VERSION) and package.json carry the
// same number; tests/consumer/check_library.py checks that they agree.
#pragma once

#define HAWOR_VERSION_MAJOR 0
#define HAWOR_VERSION_MINOR 1
#define HAWOR_VERSION_PATCH 0
#define HAWOR_VERSION_STRING "0.1.0"
/// One comparable number: 10000·major + 100·minor + patch (0.1.0 → 100).
#define HAWOR_VERSION (HAWOR_VERSION_MAJOR * 10000 + HAWOR_VERSION_MINOR * 100 + HAWOR_VERSION_PATCH)
