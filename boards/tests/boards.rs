//! The description against the chips' documents, the generated maps and the selection rules.

use nav440_boards::{
    all, feature_env, find, select, select_embassy, validate, Board, BootLoader, Image, Region,
    Uart, BOARDS,
};
use std::collections::BTreeSet;
use std::path::Path;

const KIB: u64 = 1024;

/// The memories as the documents give them: (board, flash origin, flash bytes, RAM origin,
/// RAM bytes, boot address of the vector table).
const DATA_SHEETS: &[(&str, u64, u64, u64, u64, u64)] = &[
    // ARM AN385/AN386: 4 MB SSRAM1 (code) at 0, 4 MB SSRAM2/3 at 0x2000_0000.
    ("mps2", 0, 4096 * KIB, 0x2000_0000, 4096 * KIB, 0),
    // RM0090 section 2.3, STM32F405RG: 1 MiB flash (sectors 0-11), SRAM1 112 KiB + SRAM2 16 KiB.
    (
        "stm32f405",
        0x0800_0000,
        1024 * KIB,
        0x2000_0000,
        (112 + 16) * KIB,
        0x0800_0000,
    ),
    // RM0383 section 2.3, STM32F411xE: 512 KiB flash, 128 KiB SRAM.
    (
        "nucleo-f411re",
        0x0800_0000,
        512 * KIB,
        0x2000_0000,
        128 * KIB,
        0x0800_0000,
    ),
    // RM0351 section 2.2 (memory map) and 2.3 (SRAM), STM32L475VG: 1 MiB flash; SRAM1 is
    // 96 KiB at 0x2000_0000 (SRAM2, 32 KiB at 0x1000_0000, is left out of the map).
    (
        "b-l475e-iot01a",
        0x0800_0000,
        1024 * KIB,
        0x2000_0000,
        96 * KIB,
        0x0800_0000,
    ),
    // RM0444 section 2.2 (memory map) and DS12992 (STM32G031x4/x6/x8), STM32G031K8: 64 KiB
    // flash, 8 KiB SRAM.
    (
        "nucleo-g031k8",
        0x0800_0000,
        64 * KIB,
        0x2000_0000,
        8 * KIB,
        0x0800_0000,
    ),
    // RP2040 datasheet section 2.2 (XIP at 0x1000_0000, SRAM0-5 = 4 x 64 + 2 x 4 KiB); the
    // Pico's W25Q16JV is 2 MiB; the boot ROM runs 256 bytes of boot2 before the image.
    (
        "rp-pico",
        0x1000_0000,
        2048 * KIB,
        0x2000_0000,
        (4 * 64 + 2 * 4) * KIB,
        0x1000_0000 + 256,
    ),
];

#[test]
fn the_memories_are_the_documents() {
    for &(name, flash, flash_len, ram, ram_len, vectors) in DATA_SHEETS {
        let b = find(name).unwrap();
        assert_eq!(
            (b.flash.origin, b.flash.length()),
            (flash, flash_len),
            "{name} flash"
        );
        assert_eq!((b.ram.origin, b.ram.length()), (ram, ram_len), "{name} RAM");
        assert_eq!(b.vector_table(), vectors, "{name} vector table");
    }
}

#[test]
fn every_board_has_its_module_and_its_backend() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware-example/src/board");
    for b in all() {
        assert_eq!(
            dir.join(format!("{}.rs", b.module())).is_file(),
            b.example,
            "{}",
            b.name
        );
        if let Some(backend) = &b.backend {
            assert!(dir.join(format!("{backend}.rs")).is_file(), "{}", b.name);
        }
        assert!(b.flash.contains(b.vector_table(), 0x40), "{}", b.name);
    }
}

#[test]
fn the_maps_hold_the_linked_memories() {
    let f405 = find("stm32f405").unwrap().linker_map();
    assert!(f405.contains("  FLASH : ORIGIN = 0x08000000, LENGTH = 1024K\n"));
    assert!(f405.contains("  RAM   : ORIGIN = 0x20000000, LENGTH = 128K\n"));
    assert!(!f405.contains("SECTIONS"));
    let f411 = find("nucleo-f411re").unwrap().linker_map();
    assert!(f411.contains("  FLASH : ORIGIN = 0x08000000, LENGTH = 512K\n"));
    // The NUCLEO-G031K8: the linker gets the STM32G031K6's 32 KiB of flash, the real 8 KiB.
    let g031 = find("nucleo-g031k8").unwrap();
    assert_eq!(
        (g031.flash.link_length(), g031.ram.link_length()),
        (32 * KIB, 8 * KIB)
    );
    let g031 = g031.linker_map();
    assert!(g031.contains("  FLASH : ORIGIN = 0x08000000, LENGTH = 32K\n"));
    assert!(g031.contains("  RAM   : ORIGIN = 0x20000000, LENGTH = 8K\n"));
    // The emulated boards' map is an STM32F405-sized part at 0.
    let mps2 = find("mps2").unwrap().linker_map();
    assert!(mps2.contains("  FLASH : ORIGIN = 0x00000000, LENGTH = 1024K\n"));
    assert!(mps2.contains("  RAM   : ORIGIN = 0x20000000, LENGTH = 128K\n"));
    // The Pico: boot2's 256 bytes, then the image in the rest of the 2 MiB; SRAM0-3 only.
    let pico = find("rp-pico").unwrap().linker_map();
    for line in [
        "  BOOT2 : ORIGIN = 0x10000000, LENGTH = 0x100\n",
        "  FLASH : ORIGIN = 0x10000100, LENGTH = 0x1fff00\n",
        "  RAM   : ORIGIN = 0x20000000, LENGTH = 256K\n",
        "EXTERN(BOOT2_FIRMWARE)\n",
        "  .boot2 ORIGIN(BOOT2) :\n  {\n    KEEP(*(.boot2));\n  } > BOOT2\n} INSERT BEFORE .text;\n",
    ] {
        assert!(pico.contains(line), "{line:?} not in\n{pico}");
    }
}

#[test]
fn the_module_declaration_names_the_board() {
    let decl = find("nucleo-f411re").unwrap().module_decl();
    assert!(decl.contains("macro_rules! board_modules {\n    () => {\n"));
    assert!(decl.contains(
        "        mod stm32f4_hal;\n        mod nucleo_f411re;\n        pub use nucleo_f411re::*;\n"
    ));
    assert!(decl.contains("        pub const NAME: &str = \"nucleo-f411re\";\n"));
    assert!(!decl.contains("pub use stm32f4_hal"));
    assert!(!find("mps2").unwrap().module_decl().contains("stm32f4_hal"));
}

#[test]
fn wiring_and_qemu() {
    assert_eq!(
        find("stm32f405").unwrap().wiring(),
        "USART1: TX PA9, RX PA10, AF7"
    );
    assert_eq!(
        find("rp-pico").unwrap().wiring(),
        "UART0: TX GP0, RX GP1, UART"
    );
    assert!(find("stm32f405").unwrap().runs_in_qemu());
    assert!(!find("rp-pico").unwrap().runs_in_qemu());
    assert_eq!(find("rp-pico").unwrap().probe_chip, Some("RP2040"));
    assert_eq!(find("mps2").unwrap().probe_chip, None);
    assert!(find("stm32").is_err());
}

fn vars(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn features_select_one_board() {
    assert_eq!(feature_env("board-rp-pico"), "CARGO_FEATURE_BOARD_RP_PICO");
    let name = |v: &[&str]| select(&vars(v)).map(|b| b.name);
    assert_eq!(name(&[]).unwrap(), "mps2");
    assert_eq!(name(&["CARGO_FEATURE_ONE_AXIS"]).unwrap(), "mps2");
    assert_eq!(
        name(&["CARGO_FEATURE_RTT", "CARGO_FEATURE_BOARD_NUCLEO_F411RE"]).unwrap(),
        "nucleo-f411re"
    );
    let two = name(&[
        "CARGO_FEATURE_BOARD_RP_PICO",
        "CARGO_FEATURE_BOARD_STM32F405",
    ]);
    assert!(two.unwrap_err().contains("at most one"));
    let unknown = name(&["CARGO_FEATURE_BOARD_F446"]).unwrap_err();
    assert!(unknown.contains("CARGO_FEATURE_BOARD_F446"), "{unknown}");
    let chip = |v: &[&str]| select_embassy(&vars(v)).map(|b| b.name);
    assert_eq!(chip(&["CARGO_FEATURE_STM32F411"]).unwrap(), "nucleo-f411re");
    assert_eq!(chip(&["CARGO_FEATURE_STM32F405"]).unwrap(), "stm32f405");
    assert!(chip(&[]).is_err());
    assert_eq!(
        chip(&["CARGO_FEATURE_STM32L475"]).unwrap(),
        "b-l475e-iot01a"
    );
    assert!(chip(&["CARGO_FEATURE_STM32F405", "CARGO_FEATURE_STM32F411"]).is_err());
}

/// The names of the `[features]` of the manifest `path` (from the workspace root).
fn features_of(path: &str) -> BTreeSet<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join(path)).unwrap();
    let doc: toml::Table = text.parse().unwrap();
    doc["features"]
        .as_table()
        .unwrap()
        .keys()
        .cloned()
        .collect()
}

#[test]
fn the_manifests_declare_the_described_features() {
    let board_features: BTreeSet<String> = features_of("firmware-example/Cargo.toml")
        .into_iter()
        .filter(|f| f.starts_with("board-"))
        .collect();
    let described: BTreeSet<String> = all().iter().filter_map(Board::feature).collect();
    assert_eq!(board_features, described);
    assert!(described.contains("board-rp-pico"));
    assert!(described.contains("board-nucleo-g031k8"));
    let chips: BTreeSet<String> = features_of("firmware-embassy/Cargo.toml")
        .into_iter()
        .filter(|f| f != "default")
        .collect();
    let described: BTreeSet<String> = all()
        .iter()
        .filter_map(|b| b.embassy_feature.map(str::to_owned))
        .collect();
    assert_eq!(chips, described);
    assert_eq!(described.len(), 3);
    // The embassy-only board has no firmware-example feature.
    assert_eq!(find("b-l475e-iot01a").unwrap().feature(), None);
}

const ONE: Board = Board {
    name: "a",
    part: "A",
    default: true,
    example: true,
    backend: None,
    targets: &["thumbv7em-none-eabihf"],
    probe_chip: None,
    qemu: &[],
    embassy_feature: None,
    uart: Uart {
        peripheral: "UART0",
        tx: None,
        rx: None,
        function: None,
    },
    flash: Region {
        name: "flash",
        origin: 0x0800_0000,
        kib: 64,
        link_kib: None,
    },
    ram: Region {
        name: "RAM",
        origin: 0x2000_0000,
        kib: 16,
        link_kib: None,
    },
    boot_loader: None,
    ci_image: Image::PAPER,
};

#[test]
fn a_wrong_description_is_refused() {
    validate(BOARDS).unwrap();
    validate(&[ONE]).unwrap();
    let b = |f: fn(&mut Board)| {
        let mut b = ONE;
        f(&mut b);
        b
    };
    let cases: [(Vec<Board>, &str); 9] = [
        (vec![b(|b| b.default = false)], "exactly one board"),
        (vec![ONE, b(|b| b.default = false)], "described twice"),
        (vec![b(|b| b.ram.link_kib = Some(32))], "link_kib"),
        (vec![b(|b| b.ram.origin = 0x0800_8000)], "overlap"),
        (vec![b(|b| b.name = "A_b")], "lower-case"),
        (
            vec![b(|b| b.targets = &["x86_64-unknown-linux-gnu"])],
            "thumb",
        ),
        (
            vec![b(|b| {
                b.boot_loader = Some(BootLoader {
                    bytes: 100,
                    section: ".b",
                    symbol: "B",
                })
            })],
            "aligned",
        ),
        (vec![b(|b| b.flash.kib = 1 << 30)], "32-bit"),
        (vec![b(|b| b.part = "A */ B")], "comment"),
    ];
    for (boards, want) in cases {
        let e = validate(&boards).unwrap_err();
        assert!(e.contains(want), "{want:?} not in {e:?}");
    }
}

#[test]
fn regions_contain_exactly_their_range() {
    let r = Region {
        name: "flash",
        origin: 0x0800_0000,
        kib: 1,
        link_kib: None,
    };
    assert!(r.contains(0x0800_0000, 1024));
    assert!(!r.contains(0x0800_0000, 1025));
    assert!(!r.contains(0x07ff_fffc, 8));
    assert!(r.contains(0x0800_03fc, 4));
    assert!(!r.contains(0, 4));
    let small = Region {
        link_kib: Some(1),
        kib: 2,
        ..r
    };
    assert!(small.contains(0x0800_0400, 4) && !small.link_contains(0x0800_0400, 4));
    assert!(small.link_contains(0x0800_03fc, 4));
}

#[test]
fn the_built_only_boards_images() {
    // The small part's image is the product bank without the Euler reference at profile
    // `small`; the others the default.
    let g031 = find("nucleo-g031k8").unwrap().ci_image;
    assert_eq!(
        (g031.features, g031.profile),
        (&["fixed-gains", "no-reference"][..], "small")
    );
    for name in ["nucleo-f411re", "rp-pico"] {
        let i = find(name).unwrap().ci_image;
        assert_eq!((i.features, i.profile, i.in_ci), (&[][..], "release", true));
    }
}
