// The headers that every test binary parses (GoogleTest, Eigen, OpenCV's core, the standard
// library), precompiled once for all of them (CMakeLists.txt: sg_test_pch). Only third-party and
// standard headers: a change to the project's own headers does not rebuild it.
#pragma once
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>
