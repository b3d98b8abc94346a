// Runs TLC (tlc2.TLC, same arguments, same exit code) and, every keel.progress.ms
// milliseconds, prints one line with the model checker's live counts:
//
//   @keel-progress DEPTH STATES_GENERATED DISTINCT_STATES STATES_ON_QUEUE
//
// TLC itself reports progress once a minute; keel-verify specs reads these lines to
// report every few seconds. The counts come from the MBean TLC registers for its model
// checker (tlc2.tool:type=ModelChecker), read in this process: nothing is opened to the
// outside. keel_verify/specs/tlc.py compiles this file once (javac) and caches the class.
import java.lang.management.ManagementFactory;
import javax.management.MBeanServer;
import javax.management.ObjectName;

public final class KeelTlcProgress {
    private KeelTlcProgress() {}

    public static void main(String[] args) throws Exception {
        final long periodMs = Math.max(200L, Long.getLong("keel.progress.ms", 5000L));
        final Thread probe = new Thread(() -> report(periodMs), "keel-progress");
        probe.setDaemon(true);
        probe.start();
        tlc2.TLC.main(args);
    }

    private static void report(long periodMs) {
        try {
            final MBeanServer server = ManagementFactory.getPlatformMBeanServer();
            final ObjectName checker = new ObjectName("tlc2.tool:type=ModelChecker");
            while (true) {
                Thread.sleep(periodMs);
                if (!server.isRegistered(checker)) {
                    continue; // still parsing, or computing the initial states
                }
                final String line = "@keel-progress "
                    + server.getAttribute(checker, "Progress") + " "
                    + server.getAttribute(checker, "StatesGenerated") + " "
                    + server.getAttribute(checker, "DistinctStatesGenerated") + " "
                    + server.getAttribute(checker, "StateQueueSize");
                synchronized (System.out) {
                    System.out.println(line);
                    System.out.flush();
                }
            }
        } catch (InterruptedException stopped) {
            Thread.currentThread().interrupt();
        } catch (Exception unavailable) {
            // No counts to read (another TLC version): TLC's own reports remain.
        }
    }
}
