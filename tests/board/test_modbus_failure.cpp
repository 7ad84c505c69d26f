// classify_modbus_errno: which failures cost the connection.
#include <modbus.h>

#include <catch2/catch.hpp>
#include <cerrno>

#include "lever/board/modbus_failure.hpp"

using namespace lever::board;

TEST_CASE("a timeout and a broken link reconnect, while CRC, exception and protocol errors keep the connection") {
  CHECK(classify_modbus_errno(ETIMEDOUT) == ModbusFailure::timeout);
  CHECK(classify_modbus_errno(EMBBADCRC) == ModbusFailure::bad_crc);
  for (const int exception :
       {EMBXILFUN, EMBXILADD, EMBXILVAL, EMBXSFAIL, EMBXACK, EMBXSBUSY, EMBXNACK, EMBXMEMPAR, EMBXGPATH, EMBXGTAR}) {
    CHECK(classify_modbus_errno(exception) == ModbusFailure::exception);
  }
  for (const int protocol : {EMBBADDATA, EMBBADEXC, EMBUNKEXC, EMBMDATA, EMBBADSLAVE}) {
    CHECK(classify_modbus_errno(protocol) == ModbusFailure::protocol);
  }
  for (const int link : {ECONNRESET, EPIPE, EBADF, EIO, ECONNREFUSED}) {
    CHECK(classify_modbus_errno(link) == ModbusFailure::link);
  }
  CHECK(needs_reconnect(ModbusFailure::timeout));
  CHECK(needs_reconnect(ModbusFailure::link));
  CHECK_FALSE(needs_reconnect(ModbusFailure::bad_crc));
  CHECK_FALSE(needs_reconnect(ModbusFailure::exception));
  CHECK_FALSE(needs_reconnect(ModbusFailure::protocol));
}
