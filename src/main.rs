//! The `scanmesh` command line: argument parsing, progress bars and exit
//! codes over the library; every computation lives in the library.

mod cli;

use std::process::ExitCode;

/// glibc's malloc keeps what a thread's arena freed unless it lies at the
/// arena's top, so the pages of one tile outlived it and the peak grew
/// past the plan: the 10M projection as 16 tiles peaked at 464 MiB where
/// its tiles hold 314 (`MALLOC_MMAP_THRESHOLD_` makes glibc return them).
/// `--mem` promises peak RSS, so the binary uses jemalloc, which returns
/// freed pages.
#[global_allocator]
static ALLOCATOR: tikv_jemallocator::Jemalloc = tikv_jemallocator::Jemalloc;

fn main() -> ExitCode {
    on_interrupt_clean_up_and_exit();
    exit_quietly_when_stdout_closes();
    match cli::run() {
        Ok(()) => ExitCode::SUCCESS,
        // The reader stopped early (`| head`): its choice, not a failure.
        Err(err) if cli::stdout_closed(&err) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}

/// The commands write through `cli::stdout`, which turns a closed pipe
/// into an error that ends the process quietly; a `println!` left
/// elsewhere (the run directory's script and "nothing to do" lines) panics
/// on one instead, and that panic ends it the same way, not with a panic
/// message for a reader that has gone.
fn exit_quietly_when_stdout_closes() {
    let closed_pipe = format!("(os error {})", rustix::io::Errno::PIPE.raw_os_error());
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let text = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.starts_with("failed printing to stdout") && text.ends_with(&closed_pipe) {
            scanmesh::io::cleanup::remove_registered();
            std::process::exit(0);
        }
        default(info);
    }));
}

/// SIGINT and SIGTERM end the run at once with the conventional code (130,
/// 143), after removing the scratch stores, spill files and partial
/// outputs the library registered (`scanmesh::io::cleanup`): nothing is
/// left beside the output, and no file under its final name is partial.
fn on_interrupt_clean_up_and_exit() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            let removed = scanmesh::io::cleanup::remove_registered();
            let name = if signal == SIGINT {
                "SIGINT"
            } else {
                "SIGTERM"
            };
            eprintln!("\ninterrupted ({name}): removed {removed} temporary files and directories");
            std::process::exit(128 + signal);
        }
    });
}
