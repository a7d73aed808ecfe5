// termios and poll() helpers shared by SerialPort and PseudoTerminal.
// Internal to serial_io.
#pragma once

#include <termios.h>

#include <chrono>
#include <string>

#include "serial_io/byte_stream.h"

namespace serial_io {

// Maps a baud rate in bits/s to its termios constant; 0 when not standard.
speed_t baudToSpeed(int baud);
// Inverse of baudToSpeed; 0 for an unknown constant.
int speedToBaud(speed_t speed);

// Raw 8N1, no flow control, no echo, no line discipline. Sets *error on
// failure.
bool configureRaw(int fd, speed_t speed, std::string* error);

// poll() for readability up to `timeout`, then read what is there.
ReadResult pollRead(int fd, uint8_t* buffer, size_t size, std::chrono::milliseconds timeout);

// Writes everything, waiting with poll() while the kernel buffer is full.
IoStatus writeAll(int fd, const uint8_t* data, size_t size);

}  // namespace serial_io
