// Reads a rilbed LCM log with the Java classes that lcm-gen made from src/bus/msgs/*.lcm
// (build/rilbed_lcmtypes.jar) the way lcm-spy does: each message's class is found by the
// fingerprint in its first 8 bytes. Every message must decode, and encode again to the same
// bytes; the poses, events and summary must be the run folder's (trajectories.csv,
// events.csv, summary.json, written by the same run), and the world and status consistent
// with them. Exit status 0 only when all of that holds.
//
//   java -cp rilbed_lcmtypes.jar:/usr/share/java/lcm.jar:DIR DecodeRilbedLog RUN.lcm RUN_DIR TYPE...
//
// TYPE...: the names of RILBED_LCM_TYPES (each must be in the jar). Prints one line per
// channel, a line describing the world, and "ok: ..." at the end.

import java.io.ByteArrayOutputStream;
import java.io.DataOutputStream;
import java.io.EOFException;
import java.io.IOException;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.nio.file.Paths;
import java.util.ArrayList;
import java.util.Arrays;
import java.util.HashMap;
import java.util.HashSet;
import java.util.List;
import java.util.Locale;
import java.util.Map;
import java.util.Set;
import java.util.TreeMap;

import lcm.lcm.LCMEncodable;
import lcm.logging.Log;

public final class DecodeRilbedLog {
  private static int failures = 0;

  private static void fail(String what) {
    if (failures++ < 25) System.out.println("FAIL: " + what);
  }

  private static void check(boolean ok, String what) {
    if (!ok) fail(what);
  }

  /** The fingerprint an LCM message starts with (big-endian). */
  private static long fingerprint(byte[] data) {
    long fp = 0;
    for (int i = 0; i < 8; ++i) fp = (fp << 8) | (data[i] & 0xff);
    return fp;
  }

  private static byte[] encode(LCMEncodable msg) throws IOException {
    ByteArrayOutputStream bytes = new ByteArrayOutputStream();
    msg.encode(new DataOutputStream(bytes));
    return bytes.toByteArray();
  }

  /** The fields of one CSV line as run_recorder.cpp writes it (csv_field quoting). */
  private static List<String> csvFields(String line) {
    List<String> out = new ArrayList<>();
    StringBuilder field = new StringBuilder();
    boolean quoted = false;
    for (int i = 0; i < line.length(); ++i) {
      char c = line.charAt(i);
      if (quoted) {
        if (c == '"' && i + 1 < line.length() && line.charAt(i + 1) == '"') {
          field.append('"');
          ++i;
        } else if (c == '"') {
          quoted = false;
        } else {
          field.append(c);
        }
      } else if (c == '"') {
        quoted = true;
      } else if (c == ',') {
        out.add(field.toString());
        field.setLength(0);
      } else {
        field.append(c);
      }
    }
    out.add(field.toString());
    return out;
  }

  /** The data rows of a CSV file of the run folder (no field of rilbed's holds a newline). */
  private static List<List<String>> csvRows(Path file, String header) throws IOException {
    List<String> lines = Files.readAllLines(file, StandardCharsets.UTF_8);
    check(!lines.isEmpty() && lines.get(0).equals(header), file + ": header is not " + header);
    List<List<String>> rows = new ArrayList<>();
    for (String line : lines.subList(Math.min(1, lines.size()), lines.size())) rows.add(csvFields(line));
    return rows;
  }

  /** JSON text without the whitespace outside its strings (summary.json is indented). */
  private static String compactJson(String json) {
    StringBuilder out = new StringBuilder();
    boolean inString = false;
    for (int i = 0; i < json.length(); ++i) {
      char c = json.charAt(i);
      if (inString) {
        out.append(c);
        if (c == '\\' && i + 1 < json.length()) out.append(json.charAt(++i));
        else if (c == '"') inString = false;
      } else if (c == '"') {
        inString = true;
        out.append(c);
      } else if (!Character.isWhitespace(c)) {
        out.append(c);
      }
    }
    return out.toString();
  }

  /** |a - b| within the rounding of a value printed with `decimals` decimals. */
  private static boolean near(double a, double b, int decimals) {
    return Math.abs(a - b) <= 0.5 * Math.pow(10, -decimals) + 1e-9;
  }

  private static String seconds(long utime) {
    return String.format(Locale.ROOT, "%.3f", utime / 1e6);
  }

  public static void main(String[] args) throws Exception {
    if (args.length < 3) {
      System.err.println("usage: DecodeRilbedLog RUN.lcm RUN_DIR TYPE...");
      System.exit(2);
    }
    final Path runDir = Paths.get(args[1]);

    // Every type of RILBED_LCM_TYPES is in the jar, each with its fingerprint.
    Map<Long, Class<?>> byFingerprint = new HashMap<>();
    for (String type : Arrays.copyOfRange(args, 2, args.length)) {
      Class<?> c = Class.forName("rilbed." + type);
      check(LCMEncodable.class.isAssignableFrom(c), c + " is not an LCM type");
      byFingerprint.put(c.getField("LCM_FINGERPRINT").getLong(null), c);
    }
    check(byFingerprint.size() == args.length - 2, "two types share a fingerprint");

    // Every message of the log, decoded by the class its fingerprint names.
    Map<String, Integer> counts = new TreeMap<>();
    Map<String, String> typeOf = new TreeMap<>();
    List<rilbed.world_t> worlds = new ArrayList<>();
    List<rilbed.poses_t> poses = new ArrayList<>();
    List<rilbed.event_t> events = new ArrayList<>();
    List<rilbed.status_t> statuses = new ArrayList<>();
    List<rilbed.summary_t> summaries = new ArrayList<>();
    int messages = 0;
    Log log = new Log(args[0], "r");
    for (;;) {
      Log.Event ev;
      try {
        ev = log.readNext();
      } catch (EOFException end) {
        break;
      }
      ++messages;
      final String where = ev.channel + " message " + ev.eventNumber;
      check(ev.channel.startsWith("RILBED_"), where + ": not a rilbed channel");
      if (ev.data.length < 8) {
        fail(where + ": shorter than a fingerprint");
        continue;
      }
      Class<?> type = byFingerprint.get(fingerprint(ev.data));
      if (type == null) {
        fail(where + String.format(": fingerprint %016x is none of the jar's types (lcm-spy shows ?)",
                                   fingerprint(ev.data)));
        continue;
      }
      LCMEncodable msg;
      try {
        msg = (LCMEncodable) type.getConstructor(byte[].class).newInstance((Object) ev.data);
      } catch (ReflectiveOperationException e) {
        fail(where + ": " + type.getSimpleName() + " does not decode it: " + e.getCause());
        continue;
      }
      check(Arrays.equals(encode(msg), ev.data), where + ": " + type.getSimpleName() + " does not encode it back");
      counts.merge(ev.channel, 1, Integer::sum);
      String previous = typeOf.put(ev.channel, type.getSimpleName());
      check(previous == null || previous.equals(type.getSimpleName()), ev.channel + " carries two types");
      if (msg instanceof rilbed.world_t) worlds.add((rilbed.world_t) msg);
      if (msg instanceof rilbed.poses_t) poses.add((rilbed.poses_t) msg);
      if (msg instanceof rilbed.event_t) events.add((rilbed.event_t) msg);
      if (msg instanceof rilbed.status_t) statuses.add((rilbed.status_t) msg);
      if (msg instanceof rilbed.summary_t) summaries.add((rilbed.summary_t) msg);
    }
    log.close();
    for (Map.Entry<String, Integer> e : counts.entrySet())
      System.out.println(e.getKey() + " rilbed." + typeOf.get(e.getKey()) + " " + e.getValue());
    check(!worlds.isEmpty() && !poses.isEmpty() && !statuses.isEmpty(), "no world, poses or status in the log");
    check(summaries.size() == 1, summaries.size() + " summaries, not 1");
    if (failures > 0) {
      System.out.println("FAILED: " + failures + " check(s)");
      System.exit(1);
    }

    // The world: the same every time, its arrays as long as their counts.
    rilbed.world_t w = worlds.get(0);
    StringBuilder desc = new StringBuilder(String.format(Locale.ROOT, "world %s %.2fx%.2f walls=%b robots=%d",
                                                         w.scenario, w.width_m, w.height_m, w.walls, w.num_robots));
    desc.append(" obstacles=").append(w.num_obstacles);
    for (rilbed.polyline_t p : w.obstacles) desc.append(polyline(p));
    desc.append(" tracks=").append(w.num_tracks);
    for (rilbed.polyline_t p : w.tracks) desc.append(polyline(p));
    desc.append(" beacons=").append(w.num_beacons);
    for (int i = 0; i < w.num_beacons; ++i)
      desc.append(String.format(Locale.ROOT, " (%.2f,%.2f)", w.beacon_x_m[i], w.beacon_y_m[i]));
    System.out.println(desc);
    check(w.width_m > 0 && w.height_m > 0, "field size " + w.width_m + " x " + w.height_m);
    check(w.obstacles.length == w.num_obstacles && w.tracks.length == w.num_tracks
              && w.beacon_x_m.length == w.num_beacons && w.beacon_y_m.length == w.num_beacons
              && w.robot_ids.length == w.num_robots && w.robot_real.length == w.num_robots,
          "world arrays and counts differ");
    for (rilbed.world_t other : worlds)
      check(other.scenario.equals(w.scenario) && other.width_m == w.width_m && other.height_m == w.height_m
                && Arrays.equals(other.robot_ids, w.robot_ids),
            "the world changed during the run");
    Set<Integer> ids = new HashSet<>();
    for (int id : w.robot_ids) ids.add(id);
    check(ids.size() == w.num_robots && w.num_robots > 0, "robot IDs " + Arrays.toString(w.robot_ids));

    // The poses: in the field, of the world's robots, and trajectories.csv's rows.
    List<List<String>> rows = csvRows(runDir.resolve("trajectories.csv"), "t_s,id,x_m,y_m,theta_deg,behaviour");
    int row = 0;
    long lastUtime = -1;
    for (rilbed.poses_t p : poses) {
      check(p.utime > lastUtime, "poses out of order at " + seconds(p.utime));
      lastUtime = p.utime;
      check(p.robots.length == p.num_robots && p.num_robots == w.num_robots,
            "poses at " + seconds(p.utime) + ": " + p.num_robots + " robots");
      for (rilbed.robot_pose_t r : p.robots) {
        final String at = "robot " + r.id + " at " + seconds(p.utime);
        check(ids.contains(r.id), at + ": not one of the world's robots");
        check(r.x_m >= 0 && r.x_m <= w.width_m && r.y_m >= 0 && r.y_m <= w.height_m,
              at + String.format(Locale.ROOT, ": (%.3f, %.3f) is outside the field", r.x_m, r.y_m));
        check(Double.isFinite(r.theta_rad), at + ": heading " + r.theta_rad);
        check(!r.behaviour.isEmpty() && !r.health.isEmpty(), at + ": no behaviour or health");
        if (row >= rows.size()) {
          ++row;
          continue;
        }
        List<String> f = rows.get(row++);
        double deg = Math.toDegrees(r.theta_rad) % 360.0;
        if (deg < 0) deg += 360.0;
        double dDeg = Math.abs(deg - Double.parseDouble(f.get(4)));
        check(f.size() == 6 && f.get(0).equals(seconds(p.utime)) && Integer.parseInt(f.get(1)) == r.id
                  && near(r.x_m, Double.parseDouble(f.get(2)), 5) && near(r.y_m, Double.parseDouble(f.get(3)), 5)
                  && (dDeg <= 0.005 + 1e-9 || Math.abs(dDeg - 360.0) <= 0.005 + 1e-9) && f.get(5).equals(r.behaviour),
              "trajectories.csv row " + row + " " + f + " is not " + at
                  + String.format(Locale.ROOT, " (%.5f, %.5f, %.2f deg, %s)", r.x_m, r.y_m, deg, r.behaviour));
      }
    }
    check(row == rows.size(), "poses hold " + row + " robot poses, trajectories.csv " + rows.size() + " rows");

    // The events: events.csv's rows.
    List<List<String>> eventRows = csvRows(runDir.resolve("events.csv"), "t_s,kind,id,other,detail");
    check(events.size() == eventRows.size(), events.size() + " events, events.csv has " + eventRows.size());
    for (int i = 0; i < Math.min(events.size(), eventRows.size()); ++i) {
      rilbed.event_t e = events.get(i);
      List<String> f = eventRows.get(i);
      check(f.size() == 5 && f.get(0).equals(seconds(e.utime)) && f.get(1).equals(e.kind)
                && Integer.parseInt(f.get(2)) == e.id && Integer.parseInt(f.get(3)) == e.other && f.get(4).equals(e.detail),
            "events.csv row " + (i + 1) + " " + f + " is not " + seconds(e.utime) + " " + e.kind + " " + e.id + " "
                + e.other + " " + e.detail);
    }

    // The status: the world's scenario and robots, in time order, ended at the end.
    lastUtime = -1;
    for (rilbed.status_t s : statuses) {
      check(s.utime >= lastUtime, "status out of order at " + seconds(s.utime));
      lastUtime = s.utime;
      check(s.scenario.equals(w.scenario) && s.num_robots == w.num_robots, "status at " + seconds(s.utime)
                + ": scenario " + s.scenario + ", " + s.num_robots + " robots");
      check(s.state.equals("running") || s.state.equals("paused") || s.state.equals("ended"),
            "status state " + s.state);
    }
    rilbed.status_t last = statuses.get(statuses.size() - 1);
    check(last.state.equals("ended") && !last.ended_by.isEmpty(), "the last status is " + last.state);

    // The summary: summary.json's object, and what the last status says.
    rilbed.summary_t summary = summaries.get(0);
    String fileJson = new String(Files.readAllBytes(runDir.resolve("summary.json")), StandardCharsets.UTF_8);
    check(compactJson(summary.json).equals(compactJson(fileJson)),
          "RILBED_SUMMARY is not summary.json:\n  " + summary.json + "\n  " + compactJson(fileJson));
    check(summary.json.contains("\"scenario\":\"" + w.scenario + "\"")
              && summary.json.contains("\"ended_by\":\"" + last.ended_by + "\"")
              && summary.json.contains("\"seed\":" + last.seed + ","),
          "the summary's scenario, ended_by or seed is not the status's");
    System.out.printf(Locale.ROOT, "status %s seed=%d ended_by=%s formed=%b collisions=%d%n", last.scenario, last.seed,
                      last.ended_by, last.formed, last.collisions);

    if (failures > 0) {
      System.out.println("FAILED: " + failures + " check(s)");
      System.exit(1);
    }
    System.out.printf("ok: %d messages on %d channels decoded and encoded back; %d robot poses = trajectories.csv, "
                          + "%d events = events.csv, the summary = summary.json%n",
                      messages, counts.size(), row, events.size());
  }

  private static String polyline(rilbed.polyline_t p) {
    StringBuilder s = new StringBuilder(" [");
    for (int i = 0; i < p.num_points; ++i)
      s.append(String.format(Locale.ROOT, i == 0 ? "%.2f,%.2f" : " %.2f,%.2f", p.x_m[i], p.y_m[i]));
    return s.append(p.closed ? " closed" : "").append(String.format(Locale.ROOT, " w=%.3f]", p.width_m)).toString();
  }
}
