// The participant QoS that turns on DDS Security (Cyclone's builtin authentication, access
// control and cryptography plugins) with a node's files. Internal to core/net/dds: it
// includes dds/dds.h, which only core/net/dds/*.cpp may.
#pragma once

#include <dds/dds.h>

#include "core/net/dds/dds_transport.hpp"

namespace keel::net::dds {

// A new QoS (the caller deletes it with dds_delete_qos) carrying the security properties.
dds_qos_t* new_security_qos(const SecurityFiles& files);

}  // namespace keel::net::dds
