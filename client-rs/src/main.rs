//! The `vas-client` tool.

fn main() {
    println!("vas-client");
}
