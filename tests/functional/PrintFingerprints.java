// Prints "<class> <fingerprint>" for each LCM type class named on the command line,
// reading the LCM_FINGERPRINT that lcm-gen puts in every Java type (what lcm-spy uses
// to recognise a channel's type).
public class PrintFingerprints {
  public static void main(String[] args) throws Exception {
    for (String name : args) {
      Class<?> c = Class.forName(name);
      long fp = c.getField("LCM_FINGERPRINT").getLong(null);
      System.out.println(name + " " + Long.toUnsignedString(fp));
    }
  }
}
