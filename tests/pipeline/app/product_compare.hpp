// Two products compared as a user would check "the same bits": every variable of shots.nc,
// byte for byte (strings by value), and the footprints files byte for byte.
#pragma once

#include <gtest/gtest.h>
#include <netcdf.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace glaswave::test_support {

inline std::string file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// Every variable of `expected` is in `actual` with the same type, shape and bytes.
inline void expect_same_variables(const std::filesystem::path& expected,
                                  const std::filesystem::path& actual) {
  int a = -1, b = -1, variables = 0, variables_b = 0;
  ASSERT_EQ(nc_open(expected.c_str(), NC_NOWRITE, &a), NC_NOERR) << expected;
  ASSERT_EQ(nc_open(actual.c_str(), NC_NOWRITE, &b), NC_NOERR) << actual;
  nc_inq_nvars(a, &variables);
  nc_inq_nvars(b, &variables_b);
  EXPECT_EQ(variables, variables_b);
  EXPECT_GT(variables, 40);
  for (int var = 0; var < variables; ++var) {
    char name[NC_MAX_NAME + 1] = {};
    nc_type type = NC_NAT;
    int dims = 0, dimids[NC_MAX_VAR_DIMS], var_b = -1;
    nc_inq_var(a, var, name, &type, &dims, dimids, nullptr);
    ASSERT_EQ(nc_inq_varid(b, name, &var_b), NC_NOERR) << name;
    std::size_t count = 1, length = 0;
    for (int d = 0; d < dims; ++d) {
      nc_inq_dimlen(a, dimids[d], &length);
      count *= length;
    }
    if (type == NC_STRING) {
      std::vector<char*> x(count), y(count);
      ASSERT_EQ(nc_get_var_string(a, var, x.data()), NC_NOERR);
      ASSERT_EQ(nc_get_var_string(b, var_b, y.data()), NC_NOERR);
      for (std::size_t i = 0; i < count; ++i) EXPECT_STREQ(x[i], y[i]) << name;
      nc_free_string(count, x.data());
      nc_free_string(count, y.data());
      continue;
    }
    std::size_t size = 0;
    nc_inq_type(a, type, nullptr, &size);
    std::vector<char> x(count * size), y(count * size);
    ASSERT_EQ(nc_get_var(a, var, x.data()), NC_NOERR) << name;
    ASSERT_EQ(nc_get_var(b, var_b, y.data()), NC_NOERR) << name;
    EXPECT_TRUE(x == y) << "variable " << name << " differs";
  }
  nc_close(a);
  nc_close(b);
}

// A variable's bytes (strings by value, one after another, each ending in a NUL) and whether
// its first dimension is `shot`.
inline std::pair<std::string, bool> variable_bytes(int nc, int var) {
  nc_type type = NC_NAT;
  int dims = 0, dimids[NC_MAX_VAR_DIMS];
  nc_inq_var(nc, var, nullptr, &type, &dims, dimids, nullptr);
  std::size_t count = 1, length = 0;
  char first[NC_MAX_NAME + 1] = {};
  for (int d = 0; d < dims; ++d) {
    nc_inq_dimlen(nc, dimids[d], &length);
    count *= length;
  }
  if (dims > 0) nc_inq_dimname(nc, dimids[0], first);
  std::string bytes;
  if (type == NC_STRING) {
    std::vector<char*> x(count);
    nc_get_var_string(nc, var, x.data());
    for (char* text : x) bytes += std::string(text ? text : "") + '\0';
    nc_free_string(count, x.data());
  } else {
    std::size_t size = 0;
    nc_inq_type(nc, type, nullptr, &size);
    bytes.resize(count * size);
    nc_get_var(nc, var, bytes.data());
  }
  return {bytes, std::string(first) == "shot"};
}

// shots.nc of a run split by --shots into `parts` (in order) holds the whole run's: each
// variable along `shot` is the parts' one after another, every other variable each part's.
inline void expect_same_split(const std::filesystem::path& whole,
                              const std::vector<std::filesystem::path>& parts) {
  int a = -1, variables = 0;
  ASSERT_EQ(nc_open((whole / "shots.nc").c_str(), NC_NOWRITE, &a), NC_NOERR) << whole;
  std::vector<int> part_ids;
  for (const auto& part : parts) {
    int b = -1;
    ASSERT_EQ(nc_open((part / "shots.nc").c_str(), NC_NOWRITE, &b), NC_NOERR) << part;
    part_ids.push_back(b);
  }
  nc_inq_nvars(a, &variables);
  EXPECT_GT(variables, 40);
  for (int var = 0; var < variables; ++var) {
    char name[NC_MAX_NAME + 1] = {};
    nc_inq_varname(a, var, name);
    const auto [expected, per_shot] = variable_bytes(a, var);
    std::string joined;
    for (const int b : part_ids) {
      int var_b = -1;
      ASSERT_EQ(nc_inq_varid(b, name, &var_b), NC_NOERR) << name;
      const std::string bytes = variable_bytes(b, var_b).first;
      if (per_shot)
        joined += bytes;
      else
        EXPECT_TRUE(bytes == expected) << "variable " << name << " differs in a part";
    }
    if (per_shot) {
      EXPECT_TRUE(joined == expected) << "variable " << name << " differs";
    }
  }
  nc_close(a);
  for (const int b : part_ids) nc_close(b);
}

// shots.nc's variables and footprints.geojson of two output directories.
inline void expect_same_products(const std::filesystem::path& expected,
                                 const std::filesystem::path& actual) {
  expect_same_variables(expected / "shots.nc", actual / "shots.nc");
  EXPECT_EQ(file_bytes(expected / "footprints.geojson"), file_bytes(actual / "footprints.geojson"));
}

}  // namespace glaswave::test_support
