//! How-to trial: a new packet type (X2) works through the parser, the role readers, the
//! simulator and `nav440 decode` with no code beyond its table line and its type constant.

use nav440_cli::sim::{capture_samples, encode_sample, RawSample};
use nav440_proto::{Packet, PacketType, Parser, X2Fields};

#[test]
fn x2_round_trips_through_the_table_the_parser_and_the_simulator() {
    // yaw 90 deg = 0x4000 LSB (360/2^16 deg per LSB); rate 1260/2^16 deg/s per LSB.
    let f = X2Fields {
        yaw: 0x4000,
        rate_z: 1560,
        time_itow: 123_456,
        ..Default::default()
    };
    let mut buf = [0u8; 64];
    let n = f.encode(&mut buf).unwrap();
    let mut samples = Vec::new();
    Parser::new().feed(&buf[..n], |frame| {
        let p = Packet::decode(frame).unwrap();
        assert_eq!(p.packet_type(), PacketType::X2);
        samples.push(p.yaw_sample().unwrap());
    });
    assert_eq!(samples.len(), 1);
    assert_eq!(samples[0].yaw_deg, 90.0);
    assert!((samples[0].yaw_rate_deg_s - 1560.0 * 1260.0 / 65536.0).abs() < 1e-3);
    // The simulator encodes an X2 from a sample and reads it back.
    let s = RawSample {
        angles: [10, 20, 0x4000],
        rates: [1, 2, 1560],
        itow: 123_456,
        ..RawSample::default()
    };
    let bytes = encode_sample(PacketType::X2, &s, 0).expect("X2 from the table");
    let back = capture_samples(&bytes).unwrap();
    assert_eq!(
        (back[0].angles, back[0].rates, back[0].itow),
        (s.angles, s.rates, s.itow)
    );
    // `nav440 decode` prints its fields by name.
    let dir = std::env::temp_dir().join(format!("x2-trial-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("x2.bin");
    std::fs::write(&file, &bytes).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_nav440"))
        .args(["decode", file.to_str().unwrap()])
        .output()
        .unwrap();
    let csv = String::from_utf8_lossy(&out.stdout);
    assert!(csv.lines().next().unwrap().contains("yaw"), "{csv}");
    assert!(csv.lines().nth(1).unwrap().starts_with("0,X2,"), "{csv}");
}
