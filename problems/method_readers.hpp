#pragma once
#include <string>

#include "hooke/registry.hpp"
#include "problems/table_reader.hpp"

namespace hooke {

/// Reads the [integrator] keys of `method` (a name from hooke::methods()) into that method's own
/// Options type, reporting every rule its validate() breaks through the scene key, and rejects any
/// key the method does not take. One reader per method (problems/method_readers.cpp); explicit
/// methods take no keys and return empty options.
MethodOptions read_method_options(TableReader& integrator, const std::string& method);

}  // namespace hooke
