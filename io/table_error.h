// SPDX-License-Identifier: MIT
#pragma once
// The error of io/point_table.h, in a header of its own so that the table's text parser
// (io/point_table_text.h) and the table share it without including each other. Its
// constructor is defined in io/point_table.cc.

#include <stdexcept>
#include <string>

namespace nfield::io {

// A refused table or a failed look-up. what() is `FILE:LINE:COL: message`; parts that are
// unknown (0) are left out with their colon, so a config reader can put its own location
// in front: `config.yaml:12:7: reference.file: plate.csv:7:9: expected a number, got 'abc'`.
class TableError : public std::runtime_error {
 public:
  TableError(std::string file, int line, int column, std::string message);

  const std::string& file() const { return file_; }  // as given; "F.h5:/dataset" for HDF5
  int line() const { return line_; }                   // 1-based; 0 when unknown
  int column() const { return column_; }               // 1-based byte; 0 when unknown
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_ = 0;
  int column_ = 0;
  std::string message_;
};

}  // namespace nfield::io
