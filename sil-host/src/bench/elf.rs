//! The flash and static RAM of an MCU image, read from the ELF's section headers
//! as `scripts/budgets.py` does (docs/hardware.md "Budgets").

use std::path::Path;

/// Flash and static RAM of an ELF image, bytes: the loaded sections
/// `.vector_table`, `.text`, `.rodata`, `.data` (its initial values are in
/// flash); RAM `.data`, `.bss`, `.uninit` (the stack and the defmt buffers are
/// counted by the image's own checks).
///
/// # Errors
/// The file cannot be read or is not an ELF file.
pub fn image_size(path: &Path) -> Result<(u64, u64), String> {
    use object::{Object, ObjectSection};
    let data = tables::input::read(path, tables::input::ELF_IMAGE).map_err(|e| e.to_string())?;
    let elf = object::File::parse(&*data).map_err(|e| format!("{}: not an ELF image: {e}", path.display()))?;
    let size = |names: &[&str]| -> u64 { elf.sections().filter(|s| s.name().is_ok_and(|n| names.contains(&n))).map(|s| s.size()).sum() };
    Ok((size(&[".vector_table", ".text", ".rodata", ".data"]), size(&[".data", ".bss", ".uninit"])))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_that_is_not_elf_is_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("pil");
        std::fs::write(&p, b"not an image").unwrap();
        let e = image_size(&p).unwrap_err();
        assert!(e.contains("not an ELF image"), "{e}");
        let e = image_size(&dir.path().join("missing")).unwrap_err();
        assert!(e.contains("cannot read"), "{e}");
    }

    #[test]
    fn sizes_are_read_from_the_section_headers() {
        // This test's own executable is an ELF file with .text, .rodata and .data.
        let (flash, ram) = image_size(&std::env::current_exe().unwrap()).unwrap();
        assert!(flash > 100_000 && ram > 0, "flash {flash}, ram {ram}");
    }
}
