#pragma once
// The daemon tests' helpers, all from tests/support: paths and missing-input handling, scratch
// directories, bounded waits.
#include <gtest/gtest.h>

#include "scratch_dir.hpp"
#include "test_env.hpp"
#include "wait_for.hpp"
