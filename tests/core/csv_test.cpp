// The CSV reader: numbers without the locale, rows without blanks and comments, errors at
// file:line.
#include "core/csv.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <clocale>
#include <filesystem>
#include <fstream>

#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

TEST(ParseNumber, ReadsWholeFiniteNumbersWhateverTheLocale) {
  // A locale whose decimal separator is a comma, where the machine has one: strtod and stod
  // would then read "1.5" as 1.
  for (const char* name : {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "fr_FR.utf8"})
    if (std::setlocale(LC_ALL, name)) break;
  EXPECT_EQ(parse_number("1.5"), 1.5);
  EXPECT_EQ(parse_number("+2.5e3"), 2500.0);
  EXPECT_EQ(parse_number("-0.125"), -0.125);
  for (const char* bad : {"", "1,5", "1.5 m", "abc", "nan", "inf", "1e999", "+", "0x10"})
    EXPECT_FALSE(parse_number(bad)) << bad;
  std::setlocale(LC_ALL, "C");
}

TEST(SplitCsvLine, TrimsFieldsAndKeepsEmptyOnes) {
  const auto fields = split_csv_line(" a ,b\t,, 3\r");
  ASSERT_EQ(fields.size(), 4u);
  EXPECT_EQ(fields[0], "a");
  EXPECT_EQ(fields[1], "b");
  EXPECT_EQ(fields[2], "");
  EXPECT_EQ(fields[3], "3");
}

TEST(CsvReader, SkipsBlankAndCommentLinesAndNamesTheLineOfAnError) {
  const test_support::ScratchDir dir("glaswave_csv_test");
  const fs::path file = dir / "test.csv";
  std::ofstream(file) << "# a comment\nx,y\n\n   \n1, 2\n  # another\n3,four\n";
  CsvReader csv(file, "the test file");
  std::vector<std::string_view> fields;
  ASSERT_TRUE(csv.next_row(fields));
  EXPECT_EQ(csv.place(), file.string() + ":2");
  ASSERT_TRUE(csv.next_row(fields));
  EXPECT_EQ(csv.place(), file.string() + ":5");
  EXPECT_EQ(csv.number(fields[1], "y"), 2.0);
  ASSERT_TRUE(csv.next_row(fields));
  try {
    csv.number(fields[1], "y");
    FAIL() << "\"four\" was read as a number";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_EQ(std::string(e.what()),
              file.string() + ":7: y: expected a finite number, got \"four\"");
  }
  EXPECT_FALSE(csv.next_row(fields));
  fs::remove(file);
  try {
    CsvReader missing(file, "the test file");
    FAIL() << "a missing file was opened";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), file.string() + ": cannot read the test file: no such file");
  }
}

// A spreadsheet's "CSV UTF-8" starts with a byte order mark, and Windows ends lines with CRLF:
// neither is part of a field. A FIFO nobody writes is refused before it is opened (opening it
// would wait for ever).
TEST(CsvReader, ReadsAByteOrderMarkAndCrlfAsNothingAndRefusesAFifo) {
  const test_support::ScratchDir dir("glaswave_csv_test");
  const fs::path file = dir / "excel.csv";
  std::ofstream(file, std::ios::binary) << "\xEF\xBB\xBFx,y\r\n1,2\r\n";
  CsvReader csv(file, "the test file");
  std::vector<std::string_view> fields;
  ASSERT_TRUE(csv.next_row(fields));
  ASSERT_EQ(fields.size(), 2u);
  EXPECT_EQ(fields[0], "x");
  EXPECT_EQ(fields[1], "y");
  ASSERT_TRUE(csv.next_row(fields));
  EXPECT_EQ(fields[1], "2");
  // Only at the start of the file: elsewhere it is a field's content.
  const std::string bom = "\xEF\xBB\xBF";
  std::ofstream(file, std::ios::binary) << "x,y\n" << bom << "1,2\n";
  CsvReader later(file, "the test file");
  ASSERT_TRUE(later.next_row(fields));
  ASSERT_TRUE(later.next_row(fields));
  EXPECT_EQ(fields[0], bom + "1");
  const fs::path fifo = dir / "fifo.csv";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(CsvReader(fifo, "the test file"), Error);
}

// A device is read for ever and a line of megabytes is no CSV of ours: both refused before they
// are held, naming the file (and line).
TEST(CsvReader, RefusesDevicesAndOverlongLines) {
  try {
    CsvReader zero("/dev/zero", "the test file");
    FAIL() << "/dev/zero was opened";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_EQ(std::string(e.what()),
              "/dev/zero: cannot read the test file: it is a device, not a regular file");
  }
  const test_support::ScratchDir dir("glaswave_csv_test");
  const fs::path file = dir / "long.csv";
  std::ofstream(file) << "x,y\n1,2\n" << std::string(CsvReader::max_line_bytes + 1, '7') << "\n";
  CsvReader csv(file, "the test file");
  std::vector<std::string_view> fields;
  ASSERT_TRUE(csv.next_row(fields));
  ASSERT_TRUE(csv.next_row(fields));
  try {
    csv.next_row(fields);
    FAIL() << "an overlong line was read";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              file.string() + ":3: a line longer than 4096 bytes: not the test file (CSV text)");
  }
}

TEST(FieldExcerpt, QuotesPlainShortFieldsOnly) {
  EXPECT_EQ(field_excerpt("x_m"), "\"x_m\"");
  EXPECT_EQ(field_excerpt("-1.5e3"), "\"-1.5e3\"");
  EXPECT_EQ(field_excerpt("root:$6$abc"), "a field of 11 characters");
  EXPECT_EQ(field_excerpt("\x1b[31m"), "a field of 5 characters");
  EXPECT_EQ(field_excerpt(std::string(33, 'a')), "a field of 33 characters");
  EXPECT_EQ(field_excerpt("2005-10-21T12:00:00Z", ":"), "\"2005-10-21T12:00:00Z\"");
}

}  // namespace
}  // namespace glaswave
