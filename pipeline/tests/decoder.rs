//! The front end's decoders (`nav440_pipeline::Decoder`): `OnlyA2`, the one the small part's
//! image links, gives on an A2 stream the very samples of `AllPackets` (the host's), and on a
//! stream of another attitude type (A1, N1) no sample while counting every frame. Checked on
//! the bundled captures of each type, with a corrupted A2 capture for the decode errors and
//! the time-fault capture, whose 1,040 frames hold 40 A0 (`nav440 stats` counts them).

use nav440_pipeline::{AllPackets, Decoder, Frontend, OnlyA2, Sample};

fn capture(name: &str) -> Vec<u8> {
    let p = format!("{}/../host-tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&p).unwrap_or_else(|e| panic!("{p}: {e}"))
}

/// Every sample of `bytes` through a front end with decoder `D`, and its counters.
fn samples<D: Decoder>(bytes: &[u8]) -> (Vec<Sample>, Frontend<D>) {
    let mut front = Frontend::<D>::default();
    let mut out = Vec::new();
    // In chunks of 100 bytes, as a UART delivers them.
    for chunk in bytes.chunks(100) {
        front.feed(chunk, |s| out.push(s));
    }
    front.finish(|s| out.push(s));
    (out, front)
}

#[test]
fn only_a2_gives_the_samples_of_every_packet_on_a2_streams() {
    // (capture, its A0 frames: attitude packets `OnlyA2` does not decode)
    for (name, a0) in [
        ("fig5_a2_100hz.bin", 0),
        ("fig5_a2_100hz_corrupt.bin", 0),
        ("sin5_a2_25hz_weekwrap.bin", 0),
        ("time_faults_a2_100hz.bin", 40),
    ] {
        let bytes = capture(name);
        let (all, all_front) = samples::<AllPackets>(&bytes);
        let (a2, a2_front) = samples::<OnlyA2>(&bytes);
        assert!(all.len() > 100, "{name}");
        assert_eq!(a2, all, "{name}");
        let mut expected = *all_front.counters();
        expected.attitude_packets -= a0;
        assert_eq!(*a2_front.counters(), expected, "{name}");
    }
}

#[test]
fn only_a2_estimates_nothing_from_other_types() {
    for name in ["sin5_a1_50hz.bin", "spin_n1_20hz.bin"] {
        let bytes = capture(name);
        let (all, all_front) = samples::<AllPackets>(&bytes);
        let (a2, a2_front) = samples::<OnlyA2>(&bytes);
        assert!(all.len() > 100, "{name}");
        assert!(a2.is_empty(), "{name}");
        let (c, c_all) = (a2_front.counters(), all_front.counters());
        assert_eq!(c.frames, c_all.frames, "{name}");
        assert!(c.frames > 100, "{name}");
        assert_eq!(
            (c.attitude_packets, c.samples, c.decode_errors),
            (0, 0, 0),
            "{name}"
        );
    }
}
