// Real pseudo-terminals: the emulator side and the driver side talk through
// the kernel exactly as a driver and a USB serial adapter would.
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "serial_io/pseudo_terminal.h"
#include "serial_io/serial_port.h"

namespace serial_io {
namespace {

using std::chrono::milliseconds;

std::string tempLink(const char* tag) {
  return "/tmp/serial_io_test_" + std::to_string(::getpid()) + "_" + tag;
}

std::vector<uint8_t> readExactly(ByteStream& stream, size_t count) {
  std::vector<uint8_t> out;
  uint8_t buffer[256];
  for (int tries = 0; tries < 50 && out.size() < count; ++tries) {
    const ReadResult r =
        stream.read(buffer, std::min(sizeof(buffer), count - out.size()), milliseconds(100));
    if (r.status == IoStatus::kClosed) break;
    out.insert(out.end(), buffer, buffer + r.bytes);
  }
  return out;
}

TEST(SerialIo, BinaryBytesCrossThePtyUnchangedBothWays) {
  PseudoTerminal device;
  ASSERT_TRUE(device.open(tempLink("bin"))) << device.error();
  SerialPort port;
  ASSERT_TRUE(port.open(device.devicePath(), 9600)) << port.error();

  // Every byte value, including CR, LF, XON/XOFF and ^C, must pass untouched.
  std::vector<uint8_t> all(256);
  for (int i = 0; i < 256; ++i) all[i] = static_cast<uint8_t>(i);
  ASSERT_EQ(device.write(all.data(), all.size()), IoStatus::kOk);
  EXPECT_EQ(readExactly(port, all.size()), all);
  ASSERT_EQ(port.write(all.data(), all.size()), IoStatus::kOk);
  EXPECT_EQ(readExactly(device, all.size()), all);
}

TEST(SerialIo, ReadTimesOutWithoutData) {
  PseudoTerminal device;
  ASSERT_TRUE(device.open(tempLink("timeout"))) << device.error();
  SerialPort port;
  ASSERT_TRUE(port.open(device.devicePath(), 9600)) << port.error();
  uint8_t byte;
  EXPECT_EQ(port.read(&byte, 1, milliseconds(20)).status, IoStatus::kTimeout);
}

TEST(SerialIo, EmulatorSeesTheBaudTheDriverSet) {
  PseudoTerminal device;
  ASSERT_TRUE(device.open(tempLink("baud"))) << device.error();
  SerialPort port;
  ASSERT_TRUE(port.open(device.devicePath(), 9600)) << port.error();
  EXPECT_EQ(device.peerBaud(), 9600);
  ASSERT_TRUE(port.setBaud(38400)) << port.error();
  EXPECT_EQ(device.peerBaud(), 38400);
  EXPECT_EQ(port.baud(), 38400);
}

TEST(SerialIo, UnplugIsSeenAsClosedAndReplugCanBeReopened) {
  const std::string link = tempLink("plug");
  PseudoTerminal device;
  ASSERT_TRUE(device.open(link)) << device.error();
  SerialPort port;
  ASSERT_TRUE(port.open(link, 9600)) << port.error();

  device.unplug();
  EXPECT_NE(::access(link.c_str(), F_OK), 0) << "symlink must vanish while unplugged";
  uint8_t byte;
  EXPECT_EQ(port.read(&byte, 1, milliseconds(200)).status, IoStatus::kClosed);
  SerialPort retry;
  EXPECT_FALSE(retry.open(link, 9600));
  EXPECT_NE(retry.error().find(link), std::string::npos) << "error must name the device";

  ASSERT_TRUE(device.replug()) << device.error();
  port.close();
  ASSERT_TRUE(port.open(link, 9600)) << port.error();
  const uint8_t hello[] = {0xFA, 0xFB, 0x03};
  ASSERT_EQ(device.write(hello, sizeof(hello)), IoStatus::kOk);
  EXPECT_EQ(readExactly(port, 3), std::vector<uint8_t>(hello, hello + 3));
}

TEST(SerialIo, RejectsNonStandardBaudAndRegularFileLink) {
  EXPECT_TRUE(isStandardBaud(38400));
  EXPECT_FALSE(isStandardBaud(12345));
  PseudoTerminal device;
  ASSERT_TRUE(device.open(tempLink("std"))) << device.error();
  SerialPort port;
  EXPECT_FALSE(port.open(device.devicePath(), 12345));
  EXPECT_NE(port.error().find("12345"), std::string::npos);

  const std::string file = tempLink("file");
  FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  PseudoTerminal clash;
  EXPECT_FALSE(clash.open(file));
  EXPECT_NE(clash.error().find("not a symlink"), std::string::npos);
  ::unlink(file.c_str());
}

TEST(SerialIo, UnreadOutputIsDroppedNotBlocking) {
  // Nobody reads the slave: a streaming device must not stall on a full
  // kernel buffer.
  PseudoTerminal device;
  ASSERT_TRUE(device.open(tempLink("overrun"))) << device.error();
  std::vector<uint8_t> chunk(4096, 0x55);
  for (int i = 0; i < 64; ++i) {
    ASSERT_EQ(device.write(chunk.data(), chunk.size()), IoStatus::kOk);
  }
}

}  // namespace
}  // namespace serial_io
