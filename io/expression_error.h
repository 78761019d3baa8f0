// SPDX-License-Identifier: MIT
#pragma once
// What both expression forms share, io::Expression (muparser and the compiled tape) and
// io::CompiledExpression: the error a bad text throws and the named constants a text may
// read. A header of its own so that neither form's header includes the other's (the
// constructor is defined in io/expression.cc).

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace nfield::io {

// A malformed expression or an unknown name. what() is
//   in expression 'sin(pi*q)': Unexpected token "q" found at position 7.
// position() is the 0-based offset of the offending character (as in muparser's
// message), so a config reader can turn it into a file column.
class ExpressionError : public std::runtime_error {
 public:
  ExpressionError(std::string expression, std::size_t position, std::string reason);

  const std::string& expression() const { return expression_; }
  // 0-based; std::string::npos when muparser gives none.
  std::size_t position() const { return position_; }
  // muparser's message alone.
  const std::string& reason() const { return reason_; }

 private:
  std::string expression_;
  std::size_t position_;
  std::string reason_;
};

// Named numbers an expression may read besides its variables (a config's `constants:`).
using ExpressionConstants = std::vector<std::pair<std::string, double>>;

}  // namespace nfield::io
