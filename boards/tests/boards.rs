//! The description against the chips' documents, the generated maps and the selection rules.

use nav440_boards::{
    all, check_embassy_features, check_firmware_features, feature_env, find, parse, select,
    select_embassy,
};
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
        assert!(
            dir.join(format!("{}.rs", b.module())).is_file(),
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
    assert_eq!(
        find("rp-pico").unwrap().probe_chip.as_deref(),
        Some("RP2040")
    );
    assert_eq!(find("mps2").unwrap().probe_chip, None);
    assert!(find("stm32").is_err());
}

fn vars(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn features_select_one_board() {
    assert_eq!(feature_env("board-rp-pico"), "CARGO_FEATURE_BOARD_RP_PICO");
    let name = |v: &[&str]| select(&vars(v)).map(|b| b.name.clone());
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
    let chip = |v: &[&str]| select_embassy(&vars(v)).map(|b| b.name.clone());
    assert_eq!(chip(&["CARGO_FEATURE_STM32F411"]).unwrap(), "nucleo-f411re");
    assert_eq!(chip(&["CARGO_FEATURE_STM32F405"]).unwrap(), "stm32f405");
    assert!(chip(&[]).is_err());
    assert!(chip(&["CARGO_FEATURE_STM32F405", "CARGO_FEATURE_STM32F411"]).is_err());
}

#[test]
fn the_manifests_declare_the_described_features() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    check_firmware_features(&read("firmware-example/Cargo.toml")).unwrap();
    check_embassy_features(&read("firmware-embassy/Cargo.toml")).unwrap();
    let missing = "[features]\nrtt = []\nboard-stm32f405 = []\nboard-rp-pico = []\nboard-x = []\n";
    let e = check_firmware_features(missing).unwrap_err();
    assert!(e.contains("not declared: [board-nucleo-f411re]"), "{e}");
    assert!(e.contains("not described: [board-x]"), "{e}");
}

const ONE: &str = r#"
[[board]]
name = "a"
part = "A"
default = true
targets = ["thumbv7em-none-eabihf"]
uart = { peripheral = "UART0" }
flash = { name = "flash", origin = 0x0800_0000, kib = 64 }
ram = { name = "RAM", origin = 0x2000_0000, kib = 16 }
"#;

#[test]
fn a_wrong_description_is_refused() {
    assert_eq!(parse(ONE).unwrap().len(), 1);
    let cases = [
        (ONE.replace("default = true", ""), "exactly one board"),
        (format!("{ONE}{ONE}"), "described twice"),
        (
            ONE.replace("kib = 16", "kib = 16, link-kib = 32"),
            "link-kib",
        ),
        (ONE.replace("0x2000_0000", "0x0800_8000"), "overlap"),
        (ONE.replace("name = \"a\"", "name = \"A_b\""), "lower-case"),
        (
            ONE.replace("thumbv7em-none-eabihf", "x86_64-unknown-linux-gnu"),
            "thumb",
        ),
        (
            ONE.replace(
                "kib = 64 }",
                "kib = 64 }\nboot-loader = { bytes = 100, section = \".b\", symbol = \"B\" }",
            ),
            "aligned",
        ),
        (
            ONE.replace("part = ", "chip = \"x\"\npart = "),
            "unknown field",
        ),
    ];
    for (text, want) in cases {
        let e = parse(&text).unwrap_err();
        assert!(e.contains(want), "{want:?} not in {e:?}");
    }
}

#[test]
fn regions_contain_exactly_their_range() {
    let r = nav440_boards::Region {
        name: "flash".into(),
        origin: 0x0800_0000,
        kib: 1,
        link_kib: None,
    };
    assert!(r.contains(0x0800_0000, 1024));
    assert!(!r.contains(0x0800_0000, 1025));
    assert!(!r.contains(0x07ff_fffc, 8));
    assert!(r.contains(0x0800_03fc, 4));
    assert!(!r.contains(0, 4));
}
