#pragma once
#include <string>

namespace liod {

/// Sets up spdlog on stderr. Under systemd, when stderr is the journal (stderr_is_journal), each
/// line starts with its sd-daemon(3) priority ("<3>" for an error, "<4>" a warning, "<6>" info,
/// "<7>" debug) so that `journalctl -p err` finds the errors, and carries no timestamp (journald
/// stamps every line); elsewhere lines are timestamped, coloured on a terminal. Throws
/// std::invalid_argument on an unknown level name.
void setup_logging(const std::string& level);

/// JOURNAL_STREAM names the device and inode of stderr (systemd.exec(5)).
bool stderr_is_journal();

}  // namespace liod
