// stipple — a model served over a transport, seen through the fixed-point
// client: the client end of the node stream for the programs (`stipple
// render --connect`, `stipple-handheld --connect`). It sends the hello,
// receives the startup into the client's cache, and for each camera sends
// the update and applies what comes back until the update-end: then the
// client's cache holds the view's cut and render() draws it.
//
// The transport is any platform/transport.h backend; `pump`, when given, is
// called while waiting (a loopback server in the same process steps there),
// else the socket `fd` is polled. Allocates at start-up only.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "core/cobs.h"
#include "core/protocol.h"
#include "core/stream.h"
#include "platform/transport.h"
#include "raster/client.h"

namespace stipple {

// The hello a client of this configuration sends: its screen and pixel
// format, the attributes it will use (no normals without shading, no colour
// when grey) and its cache capacity.
Hello hello_for(const ClientConfig& config);

class RemoteModel {
 public:
  struct Options {
    int fd = -1;                    // polled while waiting; -1: use pump
    bool (*pump)(void* context) = nullptr;  // false: stop waiting
    void* pump_context = nullptr;
    int timeout_ms = 15000;         // the longest wait for the server
    int silence_ms = 1000;          // serial: a silence this long while waiting means something was lost
    bool serial = false;            // COBS-framed frames; a damaged or missing one makes the
                                    // client ask for a resend from it (go-back-N)
    // When the server goes away: a new link to it (and its fd), or null to
    // give up. The client then says hello again and asks for its view.
    Transport* (*reconnect)(void* context, int* fd) = nullptr;
    void* reconnect_context = nullptr;
    std::string token;  // a pre-shared token for a server started with --token (at most 64 bytes)
    bool coded = true;  // (5) node batches entropy-coded; false: protocol 4's compact batches
  };
  // `config` sizes the client (screen, cache capacity, attributes asked for).
  // A startup that needs more than it allows — angle fields wider than its
  // max_angle_bits (a valid .spg may use up to 16 bits), wider records or
  // larger class tables — re-sizes the client for that startup before any
  // node arrives, as a local file's client is sized for its file; the
  // refusal, where even that fails, names the widths.
  bool connect(Transport& transport, const ClientConfig& config, const Options& options, std::string& error);
  // Sends the camera and waits for its update-end.
  bool view(const Camera& camera, int32_t max_size_q4, const int32_t window[4], std::string& error);
  // The same without waiting, for an interactive loop: request() sends the
  // camera (the server answers only the latest), service() takes what the
  // link has now — waiting at most `wait_ms` for it — and applies it, so the
  // cache fills while frames are drawn; converged() says when the latest
  // camera's update-end has come.
  // With a window and `accumulate` (protocol 4, on-demand refinement), the
  // server keeps the refinements of earlier windows: the cache keeps what it
  // received and only what the new window adds comes.
  bool request(const Camera& camera, int32_t max_size_q4, const int32_t window[4], std::string& error,
               bool accumulate = false);
  bool service(int wait_ms, std::string& error);
  bool converged() const;
  // How far the latest camera's answer has come (protocol 4's update-begin
  // says how many nodes each part brings): a cold start's coarse part first,
  // then the view; its share received, and the time left at the rate the
  // bytes have come since the camera was sent. Converged: share 1, none left.
  struct Progress {
    bool known = false;   // an update-begin for the latest camera has come
    bool coarse = false;  // its coarse first part (a whole picture, refined next)
    double share = 0;     // of the part's nodes received
    double seconds_left = 0;
  };
  Progress progress() const;
  bool render(const Camera& camera, uint8_t* frame, size_t stride, FrameStats* stats, std::string& error);
  // Says goodbye (a close frame, reason normal) so the server lets this
  // client go at once — over a serial line nothing else tells it.
  void close();
  Client& client() { return client_; }
  const SpgHeader& header() const { return client_.cache().header(); }
  uint64_t bytes_received() const { return bytes_received_; }
  uint64_t bytes_sent() const { return bytes_sent_; }
  uint32_t resyncs() const { return resyncs_; }  // serial: resends asked for, and hellos repeated
  uint64_t damaged() const { return damaged_; }  // serial: frames that arrived damaged
  uint32_t reconnects() const { return reconnects_; }
  uint32_t resumes() const { return resumes_; }  // reconnects that named the nodes held (protocol 3)
  uint64_t nodes_received() const { return receiver_.nodes_received(); }  // since the last (re)connect

 private:
  bool send(MessageType type, const uint8_t* payload, size_t size, std::string& error);
  enum class Awaited : uint8_t { kStartup, kUpdateEnd };
  bool done(Awaited what) const;
  bool wait(Awaited what, std::string& error);
  bool take(const uint8_t* data, size_t size, std::string& error);  // bytes from the link
  bool lost(std::string& error);       // serial: a frame did not arrive whole: ask for a resend
  bool ask_again(std::string& error);  // serial: a silence: the hello, or a resend and the camera, again
  bool reconnect(std::string& error);  // a new link, a new stream (not again from within)
  bool link_again(std::string& error);  // reconnect's work
  // The startup `frame` (a whole frame) was refused as too large: the
  // client re-made for it (a new arena), the receiver started over.
  bool fit_startup(const uint8_t* frame, size_t size, std::string& error);
  // Serial: one whole frame to the receiver (its status in `status`); a
  // startup the client is too small for re-sizes it first. False only when
  // that fails (`error` says why).
  bool receive_frame(const uint8_t* frame, size_t size, ReceiveStatus& status, std::string& error);
  std::string went_away(TransportStatus s) const;  // "the server went away: <why>"

  Transport* transport_ = nullptr;
  Options options_;
  ClientConfig config_;
  std::vector<uint8_t> early_;  // TCP: the bytes before the startup was taken
  std::vector<uint64_t> arena_;
  Client client_;
  std::vector<uint8_t> reader_storage_, frame_;
  StreamReceiver receiver_;
  uint16_t sequence_ = 0;
  uint32_t camera_sequence_ = 0, awaited_camera_ = 0;
  uint64_t bytes_sent_ = 0, bytes_received_ = 0;
  std::vector<uint8_t> cobs_storage_, cobs_out_;
  CobsDeframer deframer_;
  bool gap_ = false, has_camera_ = false, in_reconnect_ = false;
  uint32_t unacknowledged_ = 0;
  uint32_t resyncs_ = 0, reconnects_ = 0, resumes_ = 0;
  std::vector<uint32_t> held_;  // the ids a resume names
  std::vector<uint32_t> part_storage_;  // coded batches: the ids of an update's part (StreamReceiver::use_part_storage)
  uint64_t damaged_ = 0;
  Hello hello_;
  CameraUpdate last_camera_;
  Awaited awaiting_ = Awaited::kStartup;
  std::chrono::steady_clock::time_point heard_;
  std::chrono::steady_clock::time_point requested_at_{};  // the latest camera sent
  uint64_t nodes_at_request_ = 0;
  std::chrono::steady_clock::time_point sent_at_{};  // our last frame (a keep-alive follows a long quiet)  // the last bytes from the server, or our last request
};

}  // namespace stipple
