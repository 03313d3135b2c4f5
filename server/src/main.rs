//! The `vas-server` command line.

fn main() {
    println!("vas-server");
}
