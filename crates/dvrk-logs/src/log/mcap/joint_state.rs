//! `sensor_msgs/msg/JointState`: decoding from CDR (ROS 2) and JSON, encoding to CDR.
//!
//! The decoder is written out by hand rather than through serde so that a corrupted
//! length field is an error, never a multi-gigabyte allocation: every sequence length is
//! checked against the bytes that are left before anything is allocated. The encoder
//! uses the `cdr` crate (serde), an implementation independent of the decoder, so that
//! the round-trip tests check one against the other (and the anchor file checks the
//! decoder against the official Python writer).

use serde::{Deserialize, Serialize};

use super::problem::DecodeError;

/// One decoded joint state message.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct JointStateMsg {
    pub header: Header,
    pub name: Vec<String>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct Time {
    pub sec: i32,
    pub nanosec: u32,
}

impl Time {
    /// Nanoseconds since the epoch (`sec * 1e9 + nanosec`; a `nanosec` outside
    /// `[0, 1e9)` is added as it is).
    pub fn as_nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// The stamp of `ns` nanoseconds since the epoch; `None` outside the `int32` seconds
    /// range (years 1901 to 2038).
    pub fn from_nanos(ns: i64) -> Option<Time> {
        let sec = i32::try_from(ns.div_euclid(1_000_000_000)).ok()?;
        let nanosec = ns.rem_euclid(1_000_000_000) as u32;
        Some(Time { sec, nanosec })
    }
}

/// Decodes a CDR-encoded `sensor_msgs/msg/JointState` (4-byte encapsulation header,
/// then plain CDR, little- or big-endian). Trailing bytes (alignment padding) are
/// ignored.
pub(crate) fn decode_cdr(data: &[u8]) -> Result<JointStateMsg, DecodeError> {
    if data.len() < 4 {
        return Err(DecodeError::TooShort { bytes: data.len() });
    }
    let little_endian = match (data[0], data[1]) {
        (0, 0) => false,
        (0, 1) => true,
        (a, b) => {
            let kind = u16::from_be_bytes([a, b]);
            let what = match kind {
                2 | 3 => "parameter-list CDR (PL_CDR)",
                6 | 7 => "XCDR2 (CDR2)",
                8 | 9 => "XCDR2 delimited (D_CDR2)",
                10 | 11 => "XCDR2 parameter list (PL_CDR2)",
                _ => "an unknown representation",
            };
            return Err(DecodeError::Encapsulation { kind, what });
        }
    };
    let mut r = CdrReader {
        data: &data[4..],
        pos: 0,
        little_endian,
        aligned: true,
    };
    let sec = r.u32("header.stamp.sec")? as i32;
    let nanosec = r.u32("header.stamp.nanosec")?;
    let frame_id = r.string("header.frame_id")?;
    let name = r.string_seq("name")?;
    let position = r.f64_seq("position")?;
    let velocity = r.f64_seq("velocity")?;
    let effort = r.f64_seq("effort")?;
    Ok(JointStateMsg {
        header: Header {
            stamp: Time { sec, nanosec },
            frame_id,
        },
        name,
        position,
        velocity,
        effort,
    })
}

/// Decodes a `sensor_msgs/JointState` in ROS 1 serialization (what ROS 1 bags hold):
/// little-endian, no alignment, no encapsulation header; the header has a `seq` before
/// its stamp, whose seconds are unsigned.
pub(crate) fn decode_ros1(data: &[u8]) -> Result<JointStateMsg, DecodeError> {
    let mut r = CdrReader {
        data,
        pos: 0,
        little_endian: true,
        aligned: false,
    };
    let _seq = r.u32("header.seq")?;
    let sec = r.u32("header.stamp.secs")?;
    let nanosec = r.u32("header.stamp.nsecs")?;
    let frame_id = r.string("header.frame_id")?;
    let name = r.string_seq("name")?;
    let position = r.f64_seq("position")?;
    let velocity = r.f64_seq("velocity")?;
    let effort = r.f64_seq("effort")?;
    let ns = i64::from(sec) * 1_000_000_000 + i64::from(nanosec);
    let stamp = Time::from_nanos(ns).ok_or(DecodeError::Beyond2038 { sec, nanosec })?;
    Ok(JointStateMsg {
        header: Header { stamp, frame_id },
        name,
        position,
        velocity,
        effort,
    })
}

/// Encodes a joint state as little-endian CDR with its encapsulation header, as ROS 2
/// publishes it.
pub(crate) fn encode_cdr(msg: &JointStateMsg) -> Result<Vec<u8>, cdr::Error> {
    cdr::serialize::<_, _, cdr::CdrLe>(msg, cdr::Infinite)
}

/// Decodes a JSON-encoded joint state (MCAP message encoding `json`, as written by
/// Foxglove tools): the ROS field names, `header.stamp.nanosec` also accepted as `nsec`,
/// missing fields empty.
pub(crate) fn decode_json(data: &[u8]) -> Result<JointStateMsg, DecodeError> {
    #[derive(Deserialize)]
    struct JsonTime {
        #[serde(default)]
        sec: i64,
        #[serde(default, alias = "nsec")]
        nanosec: i64,
    }
    #[derive(Deserialize, Default)]
    struct JsonHeader {
        #[serde(default)]
        stamp: Option<JsonTime>,
        #[serde(default)]
        frame_id: String,
    }
    #[derive(Deserialize)]
    struct JsonJointState {
        #[serde(default)]
        header: JsonHeader,
        #[serde(default)]
        name: Vec<String>,
        #[serde(default)]
        position: Vec<f64>,
        #[serde(default)]
        velocity: Vec<f64>,
        #[serde(default)]
        effort: Vec<f64>,
    }
    let m: JsonJointState = serde_json::from_slice(data).map_err(DecodeError::Json)?;
    let stamp = m.header.stamp.ok_or(DecodeError::NoStamp)?;
    let out_of_range = DecodeError::StampRange {
        sec: stamp.sec,
        nanosec: stamp.nanosec,
    };
    let stamp = stamp
        .sec
        .checked_mul(1_000_000_000)
        .and_then(|s| s.checked_add(stamp.nanosec))
        .and_then(Time::from_nanos)
        .ok_or(out_of_range)?;
    Ok(JointStateMsg {
        header: Header {
            stamp,
            frame_id: m.header.frame_id,
        },
        name: m.name,
        position: m.position,
        velocity: m.velocity,
        effort: m.effort,
    })
}

/// A bounds-checked plain-CDR reader over the payload after the encapsulation header
/// (alignment is relative to the payload start); without alignment, the ROS 1
/// serialization.
struct CdrReader<'a> {
    data: &'a [u8],
    pos: usize,
    little_endian: bool,
    aligned: bool,
}

impl<'a> CdrReader<'a> {
    fn align(&mut self, n: usize) {
        if self.aligned {
            self.pos = self.pos.div_ceil(n) * n;
        }
    }

    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    fn take(&mut self, n: usize, field: &'static str) -> Result<&'a [u8], DecodeError> {
        if self.remaining() < n {
            return Err(DecodeError::Truncated {
                field,
                needed: n,
                offset: self.pos + 4,
                left: self.remaining(),
            });
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, DecodeError> {
        self.align(4);
        let b: [u8; 4] = self.take(4, field)?.try_into().expect("4 bytes");
        Ok(if self.little_endian {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn string(&mut self, field: &'static str) -> Result<String, DecodeError> {
        let len = self.u32(field)? as usize;
        let bytes = self.take(len, field)?;
        // The length counts a terminating NUL; tolerate its absence.
        let bytes = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        std::str::from_utf8(bytes)
            .map(str::to_owned)
            .map_err(|error| DecodeError::Utf8 { field, error })
    }

    /// A sequence length, checked against the bytes left (each element needs at least
    /// `min_element_bytes`) before anything is allocated.
    fn seq_len(
        &mut self,
        field: &'static str,
        min_element_bytes: usize,
    ) -> Result<usize, DecodeError> {
        let count = self.u32(field)? as usize;
        if count.saturating_mul(min_element_bytes) > self.remaining() {
            return Err(DecodeError::Sequence {
                field,
                count,
                left: self.remaining(),
            });
        }
        Ok(count)
    }

    fn string_seq(&mut self, field: &'static str) -> Result<Vec<String>, DecodeError> {
        let count = self.seq_len(field, 4)?;
        (0..count).map(|_| self.string(field)).collect()
    }

    fn f64_seq(&mut self, field: &'static str) -> Result<Vec<f64>, DecodeError> {
        let count = self.seq_len(field, 8)?;
        if count == 0 {
            // Fast-CDR (and the Python writer) do not align an empty sequence.
            return Ok(Vec::new());
        }
        self.align(8);
        let bytes = self.take(count * 8, field)?;
        Ok(bytes
            .chunks_exact(8)
            .map(|c| {
                let b: [u8; 8] = c.try_into().expect("8 bytes");
                if self.little_endian {
                    f64::from_le_bytes(b)
                } else {
                    f64::from_be_bytes(b)
                }
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> JointStateMsg {
        JointStateMsg {
            header: Header {
                stamp: Time {
                    sec: 1_700_000_000,
                    nanosec: 5_000_000,
                },
                frame_id: "psm".into(),
            },
            name: vec!["outer_yaw".into(), "jaw".into(), "é".into()],
            position: vec![0.1, -0.2, 1e-300],
            velocity: vec![],
            effort: vec![f64::MAX, -0.0, 3.5],
        }
    }

    #[test]
    fn cdr_round_trip_le_and_be() {
        let m = sample();
        let le = encode_cdr(&m).unwrap();
        assert_eq!(&le[..4], &[0, 1, 0, 0]);
        assert_eq!(decode_cdr(&le).unwrap(), m);
        let be = cdr::serialize::<_, _, cdr::CdrBe>(&m, cdr::Infinite).unwrap();
        assert_eq!(&be[..4], &[0, 0, 0, 0]);
        assert_eq!(decode_cdr(&be).unwrap(), m);
        // The serde decoder agrees with the hand-written one.
        let via_serde: JointStateMsg = cdr::deserialize(&le).unwrap();
        assert_eq!(via_serde, m);
    }

    #[test]
    fn every_truncation_is_an_error() {
        let le = encode_cdr(&sample()).unwrap();
        // Cutting the effort array's last element (or anything before) must fail.
        for cut in 0..le.len() - 1 {
            let r = decode_cdr(&le[..cut]);
            assert!(r.is_err(), "cut at {cut} decoded: {r:?}");
        }
    }

    #[test]
    fn huge_length_is_an_error_not_an_allocation() {
        let mut le = encode_cdr(&sample()).unwrap();
        // The name sequence count sits after sec, nanosec, frame_id (4 + 4 + 4 + 4 bytes).
        le[4 + 16..4 + 20].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = decode_cdr(&le).unwrap_err();
        assert!(e.to_string().contains("does not fit"), "{e}");
        let e = decode_cdr(&[0, 7, 0, 0, 1, 2, 3, 4]).unwrap_err();
        assert!(e.to_string().contains("XCDR2"), "{e}");
    }

    /// ROS 1 serialization written out by hand from the message definition.
    #[test]
    fn ros1() {
        let mut b = Vec::new();
        let u32le = |b: &mut Vec<u8>, v: u32| b.extend_from_slice(&v.to_le_bytes());
        u32le(&mut b, 17); // seq
        u32le(&mut b, 1_700_000_000);
        u32le(&mut b, 5_000_000);
        u32le(&mut b, 3);
        b.extend_from_slice(b"psm");
        u32le(&mut b, 2);
        for n in ["outer_yaw", "jaw"] {
            u32le(&mut b, n.len() as u32);
            b.extend_from_slice(n.as_bytes());
        }
        for values in [&[0.5, -0.25][..], &[], &[1.5, 2.0]] {
            u32le(&mut b, values.len() as u32);
            for v in values {
                b.extend_from_slice(&f64::to_le_bytes(*v));
            }
        }
        let m = decode_ros1(&b).unwrap();
        assert_eq!(m.header.stamp.as_nanos(), 1_700_000_000_005_000_000);
        assert_eq!(m.header.frame_id, "psm");
        assert_eq!(m.name, ["outer_yaw", "jaw"]);
        assert_eq!(m.position, [0.5, -0.25]);
        assert!(m.velocity.is_empty());
        assert_eq!(m.effort, [1.5, 2.0]);
        for cut in 0..b.len() {
            assert!(decode_ros1(&b[..cut]).is_err(), "cut at {cut}");
        }
    }

    #[test]
    fn json() {
        let m = decode_json(
            br#"{"header":{"stamp":{"sec":3,"nsec":7},"frame_id":""},"name":["a"],"position":[1.5],"effort":[2]}"#,
        )
        .unwrap();
        assert_eq!(m.header.stamp.as_nanos(), 3_000_000_007);
        assert_eq!(m.position, vec![1.5]);
        assert!(m.velocity.is_empty());
        assert!(decode_json(b"{\"name\":[]}").is_err());
        assert!(decode_json(b"not json").is_err());
    }

    #[test]
    fn time_conversions() {
        let t = Time::from_nanos(-1_700_000_000).unwrap();
        assert_eq!((t.sec, t.nanosec), (-2, 300_000_000));
        assert_eq!(t.as_nanos(), -1_700_000_000);
        assert!(Time::from_nanos(i64::MAX).is_none());
    }
}
