//! CDR payloads of sensor_msgs/msg/JointState, wrapped in a valid MCAP container so that
//! every input reaches the message decoder: the input is split at 0xFF 0x00 0xFF into
//! up to 16 messages, 5 ms apart. Never a panic; an accepted log is valid.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::cdr(data));
