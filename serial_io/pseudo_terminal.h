// The device side of an emulated serial device: the master end of a
// pseudo-terminal, published under a stable symlink (e.g. /tmp/lms200) that
// the real driver opens like any serial port.
//
// The master keeps its own descriptor on the slave side open so that a driver
// closing and reopening the port does not hang the emulator up. unplug() and
// replug() imitate pulling and re-inserting a USB adapter: the driver's
// descriptor starts failing with EIO/HUP and the symlink disappears until the
// new device appears.
#pragma once

#include <string>

#include "serial_io/byte_stream.h"

namespace serial_io {

class PseudoTerminal : public ByteStream {
 public:
  PseudoTerminal() = default;
  ~PseudoTerminal() override;
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;

  // Creates a pty in raw mode and points `link_path` at its slave device
  // (replacing an existing symlink, refusing to replace a regular file).
  // An empty link_path creates no symlink. Returns false and sets error().
  bool open(const std::string& link_path);

  // The device the driver should open (the symlink if any, else /dev/pts/N).
  std::string devicePath() const;
  std::string slavePath() const { return slave_path_; }

  // The line speed the peer (driver) last configured on the slave side, or 0.
  // Pseudo-terminals do not enforce baud rates; emulators use this to imitate
  // a device that only understands its current rate.
  int peerBaud() const;

  // Simulated cable pull: closes the pty and removes the symlink.
  void unplug();
  // Simulated re-insertion: a new pty under the same symlink.
  bool replug();

  ReadResult read(uint8_t* buffer, size_t size, std::chrono::milliseconds timeout) override;
  IoStatus write(const uint8_t* data, size_t size) override;
  bool isOpen() const override { return master_fd_ >= 0; }
  void close() override;
  std::string name() const override { return devicePath(); }

  const std::string& error() const { return error_; }

 private:
  void removeLink();

  int master_fd_ = -1;
  int slave_keepalive_fd_ = -1;
  std::string link_path_;
  std::string slave_path_;
  std::string error_;
};

}  // namespace serial_io
