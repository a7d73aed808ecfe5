"""Messages the tests receive without knowing their type in advance."""
import genpy.dynamic


def decode(raw):
    """A rospy.AnyMsg as the message its connection header names."""
    header = raw._connection_header
    types = genpy.dynamic.generate_dynamic(header["type"], header["message_definition"])
    return types[header["type"]]().deserialize(raw._buff)
