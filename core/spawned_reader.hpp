// Reader programs: a hostile file read for the library in a process of its own, so that a crash
// in a library under the reader (Debian 12's HDF5 1.10.8 on some corrupt files, in ways no check
// of the bytes before it covers) ends that program and refuses the file, not the caller.
//
// A library must not fork (a fork waits in every library's fork handler, and one whose lock
// another thread holds, PROJ's, hangs it): the program is started with posix_spawn, which runs no
// fork handler. Its standard input and output are one end of a socket pair, its errors stay the
// caller's, and no other descriptor of the caller's goes with it. The two talk in messages (a
// length, then the bytes); the program's first message begins with its hello (its name and the
// number of its messages' layout), so that a reader of another glaswave (an older install found
// first) is named, not misread.
//
// Each request a reader answers (opening its file is the first) has a budget of CPU, which both
// ends work out from the bytes it reads and answers (reader_cpu_budget_s): HDF5 1.10.8 spins for
// ever on some corrupt files (voxel_fuzzer found one), and a reader past its budget is ended by
// the kernel (RLIMIT_CPU's SIGXCPU), the file refused saying so.
#pragma once

#include <sys/resource.h>
#include <sys/types.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/error.hpp"

namespace glaswave {

// Where the reader program `name` is, or empty: the first of, beside the binary holding this code,
// in bin/ beside it (the pip package's glaswave/bin/ for its module), in ../libexec/glaswave/ from
// it (an installed prefix), then `also` (where the build made it, the install prefix's libexec).
std::filesystem::path find_reader_program(const std::string& name,
                                          const std::vector<std::filesystem::path>& also);

// The CPU one request of a reader program may use, seconds, for a file and answer of `bytes`
// together: kReaderBaseCpuS and a second for each kReaderBytesPerCpuS, what no legitimate file
// needs (spawned_reader.cpp gives the measurements), and short of libFuzzer's 10 s for a fuzz
// input of a few kB.
inline constexpr double kReaderBaseCpuS = 1.0;
inline constexpr double kReaderBytesPerCpuS = 16.0 * (1 << 20);
double reader_cpu_budget_s(std::uint64_t bytes);
// The CPU (user and system) that getrusage or wait4 counted, seconds.
double cpu_seconds(const rusage& used);

class SpawnedReader {
 public:
  // Starts `program` with `arguments` for `file` (named in errors), which is `what` ("the
  // granule"). A run error when it cannot be started.
  SpawnedReader(const std::filesystem::path& program, const std::vector<std::string>& arguments,
                std::string file, std::string what, std::string hello);
  // Closes the program's input (it ends there) and waits for it.
  ~SpawnedReader();
  SpawnedReader(const SpawnedReader&) = delete;
  SpawnedReader& operator=(const SpawnedReader&) = delete;

  // A request to the program.
  void send(std::string_view message);
  // The program's next message (the first without its hello). An input error naming the file
  // when the program ended without it (a crash: the signal is said; past its CPU budget: the
  // budget's rule and the CPU it used, since only the program knows what it was asked to read),
  // and from then on.
  std::string receive();
  // Waits for a program that has said all: an input error when it crashed or failed after all.
  void finish();

 private:
  [[noreturn]] void ended(const std::string& why);
  void hang_up();
  void wait();

  std::filesystem::path program_;
  std::string file_, what_, hello_;
  int socket_ = -1;
  pid_t child_ = -1;
  bool greeted_ = false;
  std::string failure_;  // the error's message once the program has failed
};

// In a reader program: its hello, written once before its first message (false when it could not
// be written); one message on `fd` (false at the end of its input, or a cut one); `message` written
// whole to `fd` (false when it could not be).
bool write_hello(int fd, std::string_view hello);
// In a reader program, first: the descriptor its hello and replies go to (its standard output as
// started; -1 when it cannot be had), standard output then pointed at standard error, so that a
// library printing to standard output cannot break a reply.
int take_reply_channel();
// In a reader program, before each request: its CPU bounded to what it has used so far plus
// reader_cpu_budget_s of `file`'s size and `answer_bytes` (past it, SIGXCPU ends it).
void bound_request_cpu(const char* file, std::uint64_t answer_bytes = 0);
bool read_message(int fd, std::string& message);
bool write_message(int fd, std::string_view message);

// A message's parts: numbers as their bytes (both ends are this machine), texts by their length,
// an Error as its kind, place and message.
class MessageOut {
 public:
  explicit MessageOut(std::string_view start = {}) : text_(start) {}
  void put_bytes(const void* data, std::size_t size) {
    text_.append(static_cast<const char*>(data), size);
  }
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    put_bytes(&value, sizeof value);
  }
  void put_string(std::string_view text) {
    put(std::uint64_t{text.size()});
    text_ += text;
  }
  void put_error(const Error& error);
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

// Reads a message's parts: a std::length_error when it is cut short.
class MessageIn {
 public:
  explicit MessageIn(const std::string& text) : text_(text) {}
  void get_bytes(void* out, std::size_t size);
  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value;
    get_bytes(&value, sizeof value);
    return value;
  }
  std::string get_string();
  Error get_error();
  std::size_t left() const { return text_.size() - at_; }

 private:
  const std::string& text_;
  std::size_t at_ = 0;
};

}  // namespace glaswave
