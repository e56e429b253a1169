//! `sil-host`: see `sil-host --help`.

fn main() {
    std::process::exit(sil_host::run(std::env::args_os()));
}
