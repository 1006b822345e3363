//! Expands a xacro file to standard output: `expand FILE [NAME:=VALUE ...] [--package NAME=DIR]`.
#![allow(clippy::print_stdout, clippy::print_stderr)]

fn main() {
    let mut opts = urdf_xacro::Options::default();
    let mut file = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let r = if a == "--package" {
            opts.add_package(&args.next().unwrap_or_default())
        } else if a.contains(":=") {
            opts.add_arg(&a)
        } else {
            file = Some(a);
            Ok(())
        };
        if let Err(e) = r {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
    let Some(file) = file else {
        eprintln!("usage: expand FILE [NAME:=VALUE ...] [--package NAME=DIR]");
        std::process::exit(2);
    };
    match urdf_xacro::expand_file(std::path::Path::new(&file), &opts) {
        Ok(x) => print!("{}", x.xml),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
