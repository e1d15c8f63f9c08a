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
    match cli::run() {
        Ok(()) => ExitCode::SUCCESS,
        // The reader stopped early (`| head`): its choice, not a failure.
        Err(err) if cli::stdout_closed(&err) => ExitCode::SUCCESS,
        Err(err) => {
            // A message that already quotes its cause (`{0}` of the error
            // below) is not followed by that cause again.
            let mut shown = err.to_string();
            eprintln!("error: {shown}");
            for cause in err.chain().skip(1) {
                let text = cause.to_string();
                if !shown.contains(&text) {
                    eprintln!("  caused by: {text}");
                    shown.push_str(&text);
                }
            }
            ExitCode::FAILURE
        }
    }
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
