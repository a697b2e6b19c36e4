#pragma once
// Checks that a Result failed with a message containing each expected fragment (file:line, the
// element, the fault), printing the whole message when it did not.

#include <gtest/gtest.h>

#include <initializer_list>
#include <string>

#include "torsion/result.h"

namespace torsion::test {

template <class T>
::testing::AssertionResult failsWith(const Result<T>& result,
                                     std::initializer_list<std::string> fragments) {
  if (result.ok()) return ::testing::AssertionFailure() << "expected an error, got success";
  const std::string& message = result.error().message;
  for (const std::string& fragment : fragments) {
    if (message.find(fragment) == std::string::npos) {
      return ::testing::AssertionFailure()
             << "error message lacks '" << fragment << "': " << message;
    }
  }
  return ::testing::AssertionSuccess() << message;
}

}  // namespace torsion::test
