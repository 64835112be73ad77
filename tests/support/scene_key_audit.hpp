#pragma once
// Included by one source of every test binary that loads scenes: after the binary's tests (one
// case per process under CTest), fails if any scene reader read a key that the key table
// (problems/scene_keys.cpp) lacks, or read it with another type, default or a narrower range.
#include <gtest/gtest.h>

#include <string>

#include "problems/scene_keys.hpp"

namespace hooke::test {

class SceneKeyAuditEnvironment : public ::testing::Environment {
 public:
  void TearDown() override {
    for (const std::string& problem : scene_key_audit().problems)
      ADD_FAILURE() << "scene key table: " << problem;
  }
};

inline ::testing::Environment* const kSceneKeyAudit =
    ::testing::AddGlobalTestEnvironment(new SceneKeyAuditEnvironment);

}  // namespace hooke::test
