fn main() -> std::process::ExitCode {
    std::process::ExitCode::from(coherent::cli::run(std::env::args_os()))
}
