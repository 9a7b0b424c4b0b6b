#include "shell/lcm_recorder.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace millwatch::shell {

// POSIX <regex.h> rather than std::regex: GCC 12's <regex> warns (maybe-uninitialized, a false
// positive inside std::function) in the -O1 sanitizer build, whose warnings are errors.
LcmRecorder::LcmRecorder(lcm_t* lcm, const std::filesystem::path& path, const std::string& channels,
                         bool invert)
    : lcm_(lcm), path_(path), invert_(invert) {
  const std::string whole = "^(" + channels + ")$";  // the whole name, as lcm-logger's -c
  if (const int err = regcomp(&channels_, whole.c_str(), REG_EXTENDED | REG_NOSUB); err != 0) {
    char what[256];
    regerror(err, &channels_, what, sizeof what);
    throw std::runtime_error("bad channel regular expression '" + channels + "': " + what);
  }
  log_ = lcm_eventlog_create(path.c_str(), "w");
  if (log_ == nullptr) {
    const int err = errno;
    regfree(&channels_);
    throw std::runtime_error(path.string() + ": cannot write (" + std::strerror(err) + ")");
  }
  subscription_ = lcm_subscribe(lcm_, ".*", &LcmRecorder::on_message, this);
  if (subscription_ == nullptr) {
    lcm_eventlog_destroy(log_);
    regfree(&channels_);
    throw std::runtime_error("cannot subscribe to LCM's channels");
  }
  lcm_subscription_set_queue_capacity(subscription_, 0);  // no limit
  last_flush_ = std::chrono::steady_clock::now();
}

LcmRecorder::~LcmRecorder() {
  if (subscription_ != nullptr) {
    lcm_unsubscribe(lcm_, subscription_);
  }
  if (log_ != nullptr) {
    lcm_eventlog_destroy(log_);
  }
  regfree(&channels_);
}

void LcmRecorder::on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* self) {
  static_cast<LcmRecorder*>(self)->record(*rbuf, channel);
}

void LcmRecorder::record(const lcm_recv_buf_t& rbuf, const char* channel) {
  // Only called while subscribed, which ends before finish() closes the log.
  if (!failure_.empty() || (regexec(&channels_, channel, 0, nullptr, 0) == 0) == invert_) {
    return;
  }
  lcm_eventlog_event_t e{};
  e.eventnum = events_;
  e.timestamp = rbuf.recv_utime;
  e.channellen = static_cast<std::int32_t>(std::strlen(channel));
  e.datalen = static_cast<std::int32_t>(rbuf.data_size);
  e.channel = const_cast<char*>(channel);  // NOLINT: the C API's event is not const
  e.data = rbuf.data;
  errno = 0;
  if (lcm_eventlog_write_event(log_, &e) != 0) {
    failure_ = path_.string() + ": cannot write event " + std::to_string(events_ + 1) + " (" +
               channel + ", " + std::to_string(rbuf.data_size) +
               " bytes): " + (errno != 0 ? std::strerror(errno) : "write failed");
    return;
  }
  ++events_;
  bytes_ += rbuf.data_size;
  ++per_channel_[channel];
}

void LcmRecorder::throw_if_failed() const {
  if (!failure_.empty()) {
    throw std::runtime_error(failure_ + "; " + std::to_string(events_) +
                             " events recorded before it");
  }
}

void LcmRecorder::flush_if_due() {
  const auto now = std::chrono::steady_clock::now();
  if (now - last_flush_ < std::chrono::seconds(1)) {
    return;
  }
  last_flush_ = now;
  errno = 0;
  if (std::fflush(log_->f) != 0) {
    failure_ = path_.string() + ": cannot write (" + std::strerror(errno) + ")";
  }
}

bool LcmRecorder::handle(int timeout_ms) {
  if (log_ == nullptr) {
    throw std::logic_error("LcmRecorder::handle after finish()");
  }
  errno = 0;
  const int status = lcm_handle_timeout(lcm_, timeout_ms);
  const int err = errno;
  flush_if_due();
  throw_if_failed();
  if (status < 0 && err != EINTR && source_is_log_) {  // read to its end
    source_ended_ = true;
    return false;
  }
  if (status < 0 && err != EINTR) {  // EINTR: a signal, which the caller reads
    throw std::runtime_error(std::string("LCM: cannot receive (") +
                             (err != 0 ? std::strerror(err) : "lcm_handle failed") + ")");
  }
  return status > 0;
}

void LcmRecorder::finish() {
  if (log_ == nullptr) {
    return;
  }
  while (failure_.empty() && lcm_handle_timeout(lcm_, 0) > 0) {
  }
  throw_if_failed();
  lcm_unsubscribe(lcm_, subscription_);
  subscription_ = nullptr;
  // lcm_eventlog_destroy closes the file without saying whether the last write reached it.
  errno = 0;
  const bool flushed = std::fflush(log_->f) == 0;
  const int err = errno;
  lcm_eventlog_destroy(log_);
  log_ = nullptr;
  if (!flushed) {
    throw std::runtime_error(path_.string() + ": cannot write (" + std::strerror(err) + "); " +
                             std::to_string(events_) + " events recorded, the last may be lost");
  }
}

}  // namespace millwatch::shell
