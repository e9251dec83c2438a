// Files written whole: to a temporary name beside the target, every write
// checked, renamed into place once complete (or, in an OutputBatch, with
// the run's other files at its commit), so that a failure leaves no
// half-written file and an existing file untouched.

#include "io/writers/atomic_file.h"

#include "radmesh/errors.h"
#include "radmesh/output_batch.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <regex>
#include <stdexcept>
#include <unordered_set>
#include <utility>

namespace radmesh {

namespace fs = std::filesystem;

namespace {

// The injected faults (inject_write_faults): bytes left before the disk
// fills, renames left before one fails; -1: none.
std::atomic<long long> g_bytes_left{-1};
std::atomic<long long> g_renames_left{-1};

// Takes `n` bytes of the injected disk's room: all of them (true), or what
// is left, in *allowed (false: the disk is full after those).
bool take_room(long long n, long long* allowed) {
  long long left = g_bytes_left.load();
  while (left >= 0) {
    const long long take = std::min(left, n);
    if (g_bytes_left.compare_exchange_weak(left, left - take)) {
      *allowed = take;
      return take == n;
    }
  }
  *allowed = n;
  return true;
}

// Whether the next rename is to fail (inject_write_faults).
bool rename_fails() {
  long long left = g_renames_left.load();
  while (left >= 0) {
    if (g_renames_left.compare_exchange_weak(left, left - 1)) return left == 0;
  }
  return false;
}

// Renames `tmp` onto `path`; the reason when it fails, empty when it did not.
std::string rename_file(const std::string& tmp, const std::string& path) {
  if (rename_fails()) return std::strerror(EIO);
  std::error_code ec;
  fs::rename(tmp, path, ec);
  return ec ? ec.message() : std::string();
}

thread_local OutputBatch::State* t_batch = nullptr;

// Makes `dir` and its missing parents, adding those it made to *made (when
// not null), parents first. IoError naming `dir` when it cannot.
void make_directories(const std::string& dir, std::vector<fs::path>* made) {
  std::error_code ec;
  std::vector<fs::path> missing;
  for (fs::path d = fs::absolute(dir, ec).lexically_normal(); !d.empty() && !fs::exists(d, ec);
       d = d.parent_path()) {
    if (d.has_filename()) missing.push_back(d);
    if (d == d.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    fs::create_directory(*it, ec);
    if (ec) throw IoError(dir + ": cannot create the directory: " + ec.message());
    if (made) made->push_back(*it);
  }
  if (!fs::is_directory(dir, ec)) throw IoError(dir + ": cannot create the directory: not a directory");
}

}  // namespace

// ---------------------------------------------------------------- the batch

struct OutputBatch::State {
  std::vector<std::pair<std::string, std::string>> files;  // (temporary, final), in order written
  std::unordered_set<std::string> finals;                  // the final names of `files`
  std::vector<std::string> removals;                       // at the commit
  std::vector<fs::path> made;                              // folders made, parents first
  bool open = true;

  // The temporary file `tmp` of `path` is finished.
  void add(const std::string& tmp, const std::string& path) {
    if (finals.insert(path).second) files.emplace_back(tmp, path);  // written again: the same temporary file
  }

  // Removes the folders made, deepest first, those left empty.
  void remove_made_folders() {
    std::error_code ec;
    for (auto it = made.rbegin(); it != made.rend(); ++it)
      if (fs::is_empty(*it, ec) && !ec) fs::remove(*it, ec);
    made.clear();
  }

  void close() {
    open = false;
    if (t_batch == this) t_batch = nullptr;
  }
};

OutputBatch::OutputBatch() : state_(std::make_unique<State>()) {
  if (t_batch != nullptr) throw std::logic_error("an OutputBatch is already open on this thread");
  t_batch = state_.get();
}

OutputBatch::~OutputBatch() {
  if (!state_->open) return;
  std::error_code ec;
  for (const auto& f : state_->files) fs::remove(f.first, ec);
  state_->files.clear();
  state_->remove_made_folders();
  state_->close();
}

void OutputBatch::create_directories(const std::string& dir) { make_directories(dir, &state_->made); }

void OutputBatch::remove_on_commit(const std::string& path) { state_->removals.push_back(path); }

void OutputBatch::commit() {
  State& s = *state_;
  s.close();
  std::error_code ec;
  for (size_t k = 0; k < s.files.size(); ++k) {
    const std::string why = rename_file(s.files[k].first, s.files[k].second);
    if (why.empty()) continue;
    for (size_t j = 0; j < k; ++j) fs::remove(s.files[j].second, ec);
    for (size_t j = k; j < s.files.size(); ++j) fs::remove(s.files[j].first, ec);
    s.remove_made_folders();
    throw IoError(s.files[k].second + ": cannot rename the finished file into place: " + why);
  }
  for (const std::string& path : s.removals)
    if (!s.finals.count(path)) fs::remove(path, ec);
}

std::vector<std::string> OutputBatch::files() const {
  std::vector<std::string> out;
  for (const auto& f : state_->files) out.push_back(f.second);
  return out;
}

// ---------------------------------------------------------------- files

namespace internal {

namespace {
constexpr std::size_t kBufferBytes = std::size_t{1} << 20;
}

CheckedFile::CheckedFile(const std::string& path, const std::string& name) : name_(name) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) throw IoError(name + ": cannot open for writing: " + std::strerror(errno));
  buffer_.reset(new char[kBufferBytes]);  // not zeroed: a small file fills only its start
  setp(buffer_.get(), buffer_.get() + kBufferBytes);
}

CheckedFile::~CheckedFile() {
  if (fd_ >= 0) ::close(fd_);
}

void CheckedFile::write_at(long long offset, const char* data, std::size_t n) {
  if (error_ != 0 || n == 0) return;
  // Only what makes the file longer takes room on a disk.
  const long long grows = std::max(0LL, offset + static_cast<long long>(n) - end_);
  long long allowed = grows;
  const bool fits = take_room(grows, &allowed);
  const std::size_t writable =
      fits ? n : static_cast<std::size_t>(std::clamp(end_ + allowed - offset, 0LL, static_cast<long long>(n)));
  std::size_t done = 0;
  while (done < writable) {
    const ssize_t w = ::pwrite(fd_, data + done, writable - done, static_cast<off_t>(offset + done));
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      error_ = w < 0 ? errno : EIO;
      break;
    }
    done += static_cast<std::size_t>(w);
  }
  end_ = std::max(end_, offset + static_cast<long long>(done));
  if (error_ == 0 && !fits) error_ = ENOSPC;
}

void CheckedFile::flush_buffer() {
  const std::size_t n = static_cast<std::size_t>(pptr() - pbase());
  write_at(start_, pbase(), n);
  start_ += static_cast<long long>(n);
  setp(buffer_.get(), buffer_.get() + kBufferBytes);
}

CheckedFile::int_type CheckedFile::overflow(int_type c) {
  flush_buffer();
  if (!traits_type::eq_int_type(c, traits_type::eof())) {
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
  }
  return traits_type::not_eof(c);
}

std::streamsize CheckedFile::xsputn(const char* s, std::streamsize n) {
  const auto count = static_cast<std::size_t>(n);
  if (count <= static_cast<std::size_t>(epptr() - pptr())) {
    std::memcpy(pptr(), s, count);
    pbump(static_cast<int>(count));
    return n;
  }
  flush_buffer();
  if (count >= kBufferBytes) {
    write_at(start_, s, count);
    start_ += static_cast<long long>(count);
  } else {
    std::memcpy(pptr(), s, count);
    pbump(static_cast<int>(count));
  }
  return n;
}

int CheckedFile::sync() {
  flush_buffer();
  return 0;
}

CheckedFile::pos_type CheckedFile::seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) {
  const long long here = start_ + (pptr() - pbase());
  if (dir == std::ios_base::cur && off == 0) return pos_type(off_type(here));  // tellp
  const long long to = (dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? here : std::max(end_, here)) + off;
  if (to < 0) return pos_type(off_type(-1));
  flush_buffer();
  start_ = to;
  return pos_type(off_type(to));
}

CheckedFile::pos_type CheckedFile::seekpos(pos_type pos, std::ios_base::openmode which) {
  return seekoff(off_type(pos), std::ios_base::beg, which);
}

void CheckedFile::close() {
  flush_buffer();
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0 && error_ == 0) error_ = errno;
  if (error_ != 0) throw IoError(name_ + ": cannot write: " + std::strerror(error_));
}

void create_output_directories(const std::string& dir) { make_directories(dir, t_batch ? &t_batch->made : nullptr); }

void remove_output_file(const std::string& path) {
  if (t_batch != nullptr) {
    t_batch->removals.push_back(path);
    return;
  }
  std::error_code ec;
  fs::remove(path, ec);
}

void prepare_output_dir(const std::string& dir, const std::string& pattern, const std::vector<std::string>& keep) {
  create_output_directories(dir);
  const std::regex ours(pattern);
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (e.is_regular_file() && std::regex_match(name, ours) && std::find(keep.begin(), keep.end(), name) == keep.end())
      remove_output_file(e.path().string());
  }
}

void inject_write_faults(long long bytes, long long renames) {
  g_bytes_left = bytes;
  g_renames_left = renames;
}


}  // namespace internal

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".tmp";
  {
    internal::CheckedFile file(tmp, path);
    try {
      std::ostream out(&file);
      write(out);
      if (!out) throw IoError(path + ": cannot write: the data could not be formatted");
      file.close();
    } catch (...) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw;
    }
  }
  if (t_batch != nullptr) {
    t_batch->add(tmp, path);
    return;
  }
  const std::string why = rename_file(tmp, path);
  if (!why.empty()) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw IoError(path + ": cannot rename the finished file into place: " + why);
  }
}

}  // namespace radmesh
